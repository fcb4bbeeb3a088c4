"""The teleop session: a person (or a script standing in) drives the simulator in real time.

:class:`TeleopSession` is the :class:`~lfdfuse.sim.simulator.CommandSource` of the one loop
(:func:`lfdfuse.sim.loop.run`). Once per control period it waits for the period's wall-clock
time (an injectable :class:`Clock`: a script runs on a simulated one, faster than real time),
polls its input sources, applies what came in — keys through the ``teleop_twist_keyboard``
state machine, client Twists through :func:`parse_twist` — and returns the held command,
clipped to the robot's limits. Client commands expire after a timeout (Foxglove's Teleop
panel repeats its command at a fixed rate while a button is held). Goals are detected live.

:func:`teleop` composes the run: the recorder (the same channels as ``simulate``), a sink for
``/teleop/input``, any extra sinks (the Foxglove stream, the terminal view), all inside one
:class:`~lfdfuse.log.writer.LogWriter`, so the MCAP appears atomically when the run ends.

Corrections (``teleop --table``): given a ``network`` command source, the session asks it every
period and drives with its proposal while it has *authority*; any key or valid client Twist
hands authority to the person at once, ``h``, a ``handback`` input or ``handback_s`` seconds
without input give it back. The session only decides who drives; what the network is (a fusion
table) and what it records is the caller's (:mod:`lfdfuse.execute.correct`).
"""

from __future__ import annotations

import math
import signal
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Literal

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.log.recorder import Recorder, provenance
from lfdfuse.log.writer import LogWriter
from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.loop import GoalSource, RunSummary, Sink, run
from lfdfuse.sim.robot import RobotParams
from lfdfuse.sim.sensors import CameraParams, SensorParams, target_reached
from lfdfuse.sim.simulator import Simulator
from lfdfuse.sources.teleop.clock import Clock, WallClock
from lfdfuse.sources.teleop.inputs import (
    Input,
    InputSource,
    TwistError,
    parse_twist,
)
from lfdfuse.sources.teleop.keys import KeyState, press
from lfdfuse.sources.teleop.record import AuthorityRecorder, InputRecorder
from lfdfuse.world.parse import World, check_pose_free

#: a run without ``--duration`` still ends: two hours of driving is a very long demonstration
MAX_DURATION_S = 7200.0
#: a goal met again within this many periods is the same achievement (as segment counts it)
GOAL_REFRACTORY_STEPS = 10
#: the shortest hold of a client command, however fast the client repeats
MIN_TIMEOUT_S = 0.5
#: the key that gives control back to the network (``teleop --table``)
HANDBACK_KEY = "h"

Authority = Literal["network", "person"]


@dataclass(frozen=True)
class TeleopOptions:
    """A teleop run. ``duration_s`` limits wall-clock time (simulated time for scripts)."""

    world: World
    input_name: str  # keyboard | foxglove | script:<file>
    seed: int = 0
    start: Pose | None = None
    duration_s: float | None = None
    #: a client command older than this is dropped and the robot stops (None: commands hold)
    twist_timeout_s: float | None = None
    keys: KeyState = field(default_factory=KeyState)
    robot: RobotParams = field(default_factory=RobotParams)
    sensors: SensorParams = field(default_factory=SensorParams)
    #: with a network driving: give control back after this many seconds without input (None: never)
    handback_s: float | None = None


@dataclass(frozen=True)
class Snapshot:
    """What the session knows after a control period (read by live views on other threads)."""

    t_s: float  # simulated time of the period
    wall_s: float  # clock time since the start
    pose: Pose
    ranges_m: np.ndarray
    command: tuple[float, float]
    keys: KeyState
    reached: tuple[tuple[str, float], ...]
    last_input: str
    inputs: int
    collisions: int
    ended: str
    authority: str = "person"  # who drove this period: "person", or "network" (teleop --table)


class TeleopSession:
    """Holds the last command; turns inputs into commands; paces, times out, detects goals."""

    def __init__(
        self,
        *,
        inputs: Sequence[InputSource],
        clock: Clock,
        robot: RobotParams,
        camera: CameraParams,
        keys: KeyState = KeyState(),
        twist_timeout_s: float | None = None,
        duration_s: float | None = None,
        network: GoalSource | None = None,
        handback_s: float | None = None,
    ) -> None:
        self.inputs = list(inputs)
        self.network = network
        self.handback_s = handback_s
        #: who drives now, and through what (an input's source; empty for the network)
        self.authority: Authority = "network" if network is not None else "person"
        self.authority_source = ""
        self._person_at = 0.0  # clock time of the person's last input
        self.person_ticks = self.network_ticks = self.takeovers = 0
        # collisions that began while the person, or the network, drove
        self.person_collisions = self.network_collisions = 0
        self.clock = clock
        self.robot = robot
        self.camera = camera
        self.keys = keys
        self.twist_timeout_s = twist_timeout_s
        self.duration_s = duration_s
        self.reached: list[tuple[str, int]] = []
        self.records: list[tuple[Input, str, tuple[float, float], float]] = []  # drained by the input sink
        self.inputs_seen = 0
        self.last_input = ""
        self.end_reason = ""
        self.snapshot: Snapshot | None = None
        self._stop_reason = ""  # set by stop(), read once per period
        self._command = (0.0, 0.0)
        self._twist_at: float | None = None  # clock time of the client command being held
        self._interval_s: float | None = None  # smoothed interval between client commands
        self._t0: float | None = None
        self._k0 = 0
        self._met_last: dict[str, int] = {}
        self._collisions = 0
        self._blocked = False

    # -- control from other threads or signal handlers ---------------------------------------
    def stop(self, reason: str) -> None:
        """End the run at the next period, from another thread or a signal handler.

        It only sets an attribute. A lock (a ``threading.Event``) here deadlocked when a signal's
        handler ran while the loop held the event's own lock inside its wait: the run never ended.
        """
        if not self._stop_reason:
            self._stop_reason = reason or "stopped"

    @property
    def done(self) -> bool:
        return bool(self.end_reason)

    # -- the command source -------------------------------------------------------------------
    def command(self, obs: Observation) -> tuple[float, float]:
        t = self._pace(obs.k)
        # the network senses and proposes every period, also while the person drives: its goals,
        # landmarks and odometry stay current, and the log shows what it would have done
        proposal = self.network.command(obs) if self.network is not None else None
        for src in self.inputs:
            for inp in src.poll(t):
                self._apply(inp, t)
        if (
            self.authority == "person"
            and self.network is not None
            and self.handback_s is not None
            and not self.end_reason
            and t - self._person_at >= self.handback_s - 1e-9
        ):
            self._hand_back(Input("handback", f"no input for {self.handback_s:g} s", "session"), t)
        if self._twist_at is not None and t - self._twist_at > self._timeout():
            self._twist_at = None
            self._set((0.0, 0.0))
            self._note(Input("message", "", "timeout"), "timeout", t)
        if not self.end_reason:
            if self.network is not None and self.network.done:
                self._end("task complete", t)
            elif self._stop_reason:
                self._end(self._stop_reason, t)
            elif self.duration_s is not None and t >= self.duration_s - 1e-9:
                self._end("duration", t)
        self._goals(obs)
        if obs.blocked and not self._blocked:
            self._collisions += 1
            if self.authority == "person":
                self.person_collisions += 1
            else:
                self.network_collisions += 1
        self._blocked = obs.blocked
        if self.authority == "person":
            self.person_ticks += 1
        else:
            self.network_ticks += 1
        if self.end_reason:
            cmd = (0.0, 0.0)
        elif self.authority == "network" and proposal is not None:
            cmd = proposal
        else:
            cmd = self._command
        self.snapshot = Snapshot(
            t_s=obs.t_ns / 1e9,
            wall_s=t,
            pose=obs.pose,
            ranges_m=obs.reading.ranges_m,
            command=cmd,
            keys=self.keys,
            reached=tuple((n, k * self.robot.dt_s) for n, k in self.reached),
            last_input=self.last_input,
            inputs=self.inputs_seen,
            collisions=self._collisions,
            ended=self.end_reason,
            authority=self.authority,
        )
        return cmd

    def _pace(self, k: int) -> float:
        """Wait for period ``k``'s time; returns the clock time since the start (s)."""
        now = self.clock.now()
        if self._t0 is None:
            self._t0, self._k0 = now, k
        due = self._t0 + (k - self._k0) * self.robot.dt_s
        if now > due + 0.5:
            # fell behind (a stalled terminal, a slow machine): resume the pace from here
            # instead of rushing through the missed periods
            self._t0, self._k0, due = now, k, now
        self.clock.wait_until(due)
        return max(0.0, self.clock.now() - self._t0)

    def _apply(self, inp: Input, t: float) -> None:
        if inp.kind == "end":  # a script's end, stated or implied, is nobody's input
            self._end(inp.text or "end", t, inp)
            return
        self.inputs_seen += 1
        if self.end_reason:
            self._note(inp, "ignored", t)
            return
        if inp.kind == "handback" or (
            self.network is not None and inp.kind == "key" and inp.text == HANDBACK_KEY
        ):
            if self.network is None:
                self._note(inp, "ignored (no network to hand back to)", t)
            else:
                self._hand_back(inp, t)
            return
        if inp.kind == "key":
            eff = press(self.keys, inp.text, self.robot.drive)
            self.keys = eff.state
            self._twist_at = None
            if eff.quit:
                self._set((0.0, 0.0))
                self._end(f"key {inp.text}", t, inp)
                return
            self._set(eff.state.command)
            self._take(inp, t)
            effect = "stop" if eff.state.command == (0.0, 0.0) else "move"
            if inp.text in ("q", "z", "w", "x", "e", "c"):
                effect = "scale"
            self._note(inp, effect if eff.known else "stop (unbound key)", t)
            self.last_input = inp.text
            return
        try:
            v, w = parse_twist(inp.text)
        except TwistError as exc:
            self._note(inp, f"invalid: {exc}", t)
            return
        repeat = self._twist_at is not None and self._command == self._clip((v, w))
        self._set((v, w))
        self._take(inp, t)
        if self.twist_timeout_s is not None:
            if repeat and self._twist_at is not None:
                # a repeat of the held command: the client's publish interval
                gap = t - self._twist_at
                self._interval_s = gap if self._interval_s is None else 0.7 * self._interval_s + 0.3 * gap
            self._twist_at = t
        self._note(inp, "stop" if self._command == (0.0, 0.0) else "move", t)
        self.last_input = f"twist v={v:+.2f} w={w:+.2f}"

    def _take(self, inp: Input, t: float) -> None:
        """The person's input takes (or keeps) control."""
        self._person_at = t
        if self.authority != "person":
            self.authority, self.authority_source = "person", inp.source
            self.takeovers += 1

    def _hand_back(self, inp: Input, t: float) -> None:
        """Control goes back to the network; the person's held direction is dropped (speeds stay)."""
        self.authority, self.authority_source = "network", ""
        self.keys = KeyState(speed_mps=self.keys.speed_mps, turn_rps=self.keys.turn_rps)
        self._twist_at = None
        self._set((0.0, 0.0))
        self._note(inp, "handback", t)
        self.last_input = "handback"

    def _timeout(self) -> float:
        """How long a client command holds: ``twist_timeout_s``, or less for a client that
        repeats faster (three of its intervals, at least half a second), so the robot stops soon
        after a Teleop panel button is released."""
        assert self.twist_timeout_s is not None
        if self._interval_s is None:
            return self.twist_timeout_s
        return min(self.twist_timeout_s, max(MIN_TIMEOUT_S, 3.0 * self._interval_s))

    def _clip(self, cmd: tuple[float, float]) -> tuple[float, float]:
        d = self.robot.drive
        v = min(max(cmd[0], -d.v_max_mps), d.v_max_mps)
        w = min(max(cmd[1], -d.omega_max_rps), d.omega_max_rps)
        return v + 0.0, w + 0.0

    def _set(self, cmd: tuple[float, float]) -> None:
        self._command = self._clip(cmd)

    def _note(self, inp: Input, effect: str, t: float) -> None:
        self.records.append((inp, effect, self._command, t))

    def _end(self, reason: str, t: float, inp: Input | None = None) -> None:
        if self.end_reason:
            return
        self.end_reason = reason
        self._command = (0.0, 0.0)
        self.last_input = reason
        self._note(inp or Input("end", reason, "session"), "end", t)

    def _goals(self, obs: Observation) -> None:
        """Record each target as it comes within reach (a rising edge, as segment sees it)."""
        for d in obs.reading.detections:
            if not target_reached(d.range_m, self.camera):
                continue
            last = self._met_last.get(d.name)
            if last is None or obs.k - last > GOAL_REFRACTORY_STEPS:
                self.reached.append((d.name, obs.k))
            self._met_last[d.name] = obs.k


@dataclass(frozen=True)
class TeleopSummary:
    run: RunSummary
    ended: str
    inputs: int


def make_session(
    opts: TeleopOptions,
    *,
    inputs: Sequence[InputSource],
    clock: Clock | None = None,
    network: GoalSource | None = None,
) -> TeleopSession:
    """The session for a run: real time unless a clock is given (a :class:`~lfdfuse.sources.teleop.clock.SimClock` for scripts);
    with ``network``, the network drives until the person takes over."""
    if opts.duration_s is not None and not (opts.duration_s > 0 and math.isfinite(opts.duration_s)):
        raise ConfigError("duration must be a positive number of seconds")
    if opts.handback_s is not None and not (opts.handback_s > 0 and math.isfinite(opts.handback_s)):
        raise ConfigError("handback must be a positive number of seconds")
    return TeleopSession(
        inputs=inputs,
        clock=clock or WallClock(),
        robot=opts.robot,
        camera=opts.sensors.camera,
        keys=opts.keys,
        twist_timeout_s=opts.twist_timeout_s,
        duration_s=opts.duration_s,
        network=network,
        handback_s=opts.handback_s,
    )


def teleop(
    opts: TeleopOptions,
    *,
    session: TeleopSession,
    out: str | Path,
    sinks: Sequence[Sink] = (),
    log_sinks: Sequence[Callable[[LogWriter], Sink]] = (),
    metadata: Mapping[str, str] | None = None,
) -> TeleopSummary:
    """Run ``session`` until a key, the duration, or :meth:`TeleopSession.stop`; record ``out``.

    The MCAP has the channels of ``simulate`` plus ``/teleop/input`` (and, with a network,
    ``/lfd/authority``), provenance ``teacher: human`` plus ``metadata``; ``log_sinks`` make
    further sinks that write to the log. It is written atomically when the run ends (an
    exception leaves nothing).
    """
    start = opts.start or Pose(*opts.world.start)
    check_pose_free(opts.world, start.as_tuple(), what="start pose", radius=opts.robot.radius_m)
    rng = np.random.default_rng(opts.seed)
    meta = provenance(
        command="teleop",
        seed=opts.seed,
        world=opts.world,
        sensors=opts.sensors,
        dt_s=opts.robot.dt_s,
        teacher="human",
        input=opts.input_name,
        start=",".join(repr(v) for v in start.as_tuple()),
        **(metadata or {}),
    )
    sim = Simulator(opts.world, rng, opts.sensors, opts.robot)
    # the session ends a --duration run by its clock (simulated time never runs ahead of it);
    # the loop's own limit only bounds a run without one
    limit = min(opts.duration_s or MAX_DURATION_S, MAX_DURATION_S) + 1.0
    with LogWriter(out, metadata=meta) as log:
        recorders: list[Sink] = [
            Recorder(log, world=opts.world, sensors=opts.sensors),
            InputRecorder(log, session),
        ]
        if session.network is not None:
            recorders.append(AuthorityRecorder(log, session))
        summary = run(
            sim,
            session,
            start=start,
            duration_s=limit,
            sinks=[*recorders, *(make(log) for make in log_sinks), *sinks],
            out=str(out),
        )
        ended = session.end_reason or "time limit"
        log.metadata["ended"] = ended
        log.metadata["goals"] = ",".join(f"{n}@{k * opts.robot.dt_s:.1f}" for n, k in session.reached)
    return TeleopSummary(summary, ended, session.inputs_seen)


@contextmanager
def stop_on_signals(
    session: TeleopSession, signals: Sequence[signal.Signals] = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
) -> Iterator[None]:
    """End the session (and so save the demo) on these signals; restore the old handlers after.

    Call from the main thread (Python delivers signals there).
    """
    old: dict[signal.Signals, object] = {}

    def handler(signum: int, frame: FrameType | None) -> None:
        session.stop(f"signal {signal.Signals(signum).name}")

    try:
        for s in signals:
            old[s] = signal.signal(s, handler)
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)  # type: ignore[arg-type]
