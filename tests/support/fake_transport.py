"""An in-process robot behind ``drive``'s transport seam: no socket, no protocol, no thread.

:class:`FakeRobot` is the simulator stepped by the commands ``drive`` sends; its
:meth:`~FakeRobot.transport` is a :class:`~lfdfuse.drive.transport.Transport` whose links hand
``drive``'s run the robot's sensing as decoded records — the scan in ``base_link``, odometry,
and with ``camera`` the target detections — and take its commands. ``lockstep`` steps the
simulator as soon as a command answers a scan (faster than real time, the same closed loop);
otherwise it runs at the robot's 10 Hz on the event loop's clock. Stamps are the robot's wall
clock, as on a real robot: ``epoch_ns`` plus the time since its first message (the simulator's
own time only moves the physics, so a lockstep run's stamps do not race ahead). Faults: scans pause for a
while (:meth:`pause_scans`), the robot refuses connections (``reachable``).
"""

from __future__ import annotations

import asyncio
import math
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Self

import numpy as np

from lfdfuse.drive.decode import JSON_MAX_RANGE_M, LiveOdom, LiveScan, LiveTargets, Role
from lfdfuse.drive.options import Stopper
from lfdfuse.drive.transport import Arrival, Event, Lost, Ready, Warn
from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Observation
from lfdfuse.robot.records import ScanRecord, no_return
from lfdfuse.sim.loop import side_beam_index
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.world.model import World

EPOCH_NS = 1_700_000_000_000_000_000


@dataclass(frozen=True)
class Received:
    """A command as the robot got it."""

    wall_s: float
    tick: int
    v_mps: float
    omega_rps: float
    stamp_ns: int


@dataclass
class FakeRobot:
    """See the module docstring. ``seconds`` of robot time, then ``stopper.stop('robot done')``."""

    world: World
    seconds: float
    stopper: Stopper | None = None
    start: Pose | None = None
    lockstep: bool = True
    camera: bool = True
    seed: int = 0
    epoch_ns: int = EPOCH_NS
    reachable: bool = True
    command_timeout_s: float = 1.0  # lockstep: how long a scan waits for its command
    received: list[Received] = field(default_factory=list)
    poses: list[tuple[float, float, float]] = field(default_factory=list)
    sides: list[tuple[float, float]] = field(default_factory=list)  # laser range at +90°, −90°
    scan_walls: list[float] = field(default_factory=list)  # when each scan was handed over
    links: int = 0

    def __post_init__(self) -> None:
        self.sensors = SensorParams()
        self.sim = Simulator(self.world, np.random.default_rng(self.seed), self.sensors)
        angles = self.sensors.laser.geometry.angles
        self._beams = side_beam_index(angles, math.pi / 2), side_beam_index(angles, -math.pi / 2)
        self.tick = 0
        self.cmd = (0.0, 0.0)
        self._obs: Observation | None = None
        self._pauses: list[tuple[float, float]] = []  # (from, until) robot seconds without scans
        self.scanned = False  # the last period had a scan
        self.stamps: list[int] = []  # of each period's messages
        self._t0 = 0.0
        self.collisions = 0

    def transport(self) -> FakeTransport:
        return FakeTransport(self)

    def pause_scans(self, at_s: float, for_s: float) -> None:
        """No scans from robot time ``at_s`` for ``for_s`` seconds (odometry goes on)."""
        self._pauses.append((at_s, at_s + for_s))

    def paused(self, t_s: float) -> bool:
        return any(a <= t_s < b for a, b in self._pauses)

    @property
    def done(self) -> bool:
        return self.tick >= round(self.seconds / self.sim.robot.dt_s)

    def observe(self) -> list[Event]:
        """The robot's sensing now, as the arrivals of one period."""
        if self._obs is None:
            self._obs = self.sim.reset(self.start)
        obs = self._obs
        if not self.stamps:
            self._t0 = time.monotonic()
        t = self.epoch_ns + round((time.monotonic() - self._t0) * 1e9)
        t = max(t, self.stamps[-1] + 1) if self.stamps else t
        self.stamps.append(t)
        p, r = obs.pose, obs.reading
        self.poses.append(p.as_tuple())
        self.sides.append((float(r.ranges_m[self._beams[0]]), float(r.ranges_m[self._beams[1]])))
        now, cpu = time.perf_counter(), time.thread_time()
        events: list[Event] = [Arrival(Role.ODOM, LiveOdom(t, p.x, p.y, p.theta, "base_link"), now, cpu)]
        if self.camera:
            events.append(Arrival(Role.TARGETS, LiveTargets(t, r.detections), now, cpu))
        self.scanned = not self.paused(obs.t_ns / 1e9)
        if self.scanned:
            g = self.sensors.laser.geometry
            ranges = no_return(np.asarray(r.ranges_m, dtype=np.float64), max_m=JSON_MAX_RANGE_M)
            rec = ScanRecord(t, g.start_rad, g.increment_rad, ranges, JSON_MAX_RANGE_M)
            events.append(Arrival(Role.SCAN, LiveScan("base_link", rec), now, cpu))
        return events

    def step(self) -> None:
        self._obs = self.sim.step(*self.cmd)
        self.tick += 1
        self.collisions = self.sim.collisions
        if self.done and self.stopper is not None:
            self.stopper.stop("robot done")


class FakeTransport:
    """Links to a :class:`FakeRobot` (``fake://`` in notes)."""

    url = "fake://robot"

    def __init__(self, robot: FakeRobot) -> None:
        self.robot = robot

    async def connect(self, *, timeout_s: float, warn: Warn) -> FakeLink:
        await asyncio.sleep(0)
        if not self.robot.reachable:
            raise Lost("refused")
        self.robot.links += 1
        return FakeLink(self.robot)


class FakeLink:
    """One link: :class:`Ready` first, then each period's arrivals; commands step the robot."""

    def __init__(self, robot: FakeRobot) -> None:
        self.robot = robot
        self.queue: deque[Event] = deque([Ready(camera=robot.camera, command="fake Twist")])
        self.answered = asyncio.Event()  # a command came since the last scan
        self.closed = False
        self._next_s = time.monotonic()

    def __aiter__(self) -> Self:
        return self

    async def __anext__(self) -> Event:
        r = self.robot
        while not self.queue:
            if r.done:
                await asyncio.Event().wait()  # the robot's time is over: nothing more comes
            if r.tick > 0 or r.poses:  # a period has been served: wait for its end, then step
                await self._period()
                r.step()
            self.answered.clear()
            self.queue.extend(r.observe())
        ev = self.queue.popleft()
        if isinstance(ev, Arrival) and ev.role is Role.SCAN:
            r.scan_walls.append(time.monotonic())
        return ev

    async def _period(self) -> None:
        r = self.robot
        dt = r.sim.robot.dt_s
        if not r.lockstep:
            self._next_s += dt
            await asyncio.sleep(max(0.0, self._next_s - time.monotonic()))
        elif r.scanned:
            try:
                await asyncio.wait_for(self.answered.wait(), r.command_timeout_s)
            except TimeoutError:
                pass
        else:
            await asyncio.sleep(dt)

    async def send(self, v_mps: float, omega_rps: float, stamp_ns: int) -> None:
        if self.closed:
            raise Lost("closed")
        r = self.robot
        r.received.append(Received(time.monotonic(), r.tick, v_mps, omega_rps, stamp_ns))
        r.cmd = (v_mps, omega_rps)
        self.answered.set()

    def not_ready(self) -> str:
        return "the fake robot is never late"

    async def close(self) -> None:
        self.closed = True
