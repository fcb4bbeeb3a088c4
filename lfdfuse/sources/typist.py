"""A simulated typist: a scripted teacher pressing keys as a person at a keyboard would (``simulate --keys PERIOD``, DESIGN §9).

:class:`KeyboardPerson` wraps any command source that knows where it wants to go (a style or
task teacher) and drives the robot the way a person at ``teleop_twist_keyboard`` does: every
``period_s`` seconds (jittered, seeded) it looks at what the teacher wants *now* — as of
``reaction_s`` ago: people react late — and presses the forward key whose command points
nearest to it (``i`` straight, ``u``/``o`` arcs, ``j``/``l`` turns in place), then holds that
key's command until the next press. The key table and the held speeds are those of
:mod:`lfdfuse.sources.teleop.keys`; "nearest" compares the headings the commands stand for
under the drive mapping (:func:`~lfdfuse.control.command.command_to_heading`), so a wanted turn of
more than about 65° is a turn in place. The loop runs on the simulated clock (faster than real
time); every press is recorded on ``/teleop/input`` as a teleop log records it.

That is one person, ``steady``. People differ: :class:`KeyboardParams` is a person model and
:data:`PERSONS` the zoo of named ones (``simulate --person NAME``, or each parameter set on its
own). A person reacts ``reaction_s`` late (0 to 0.6 s in the zoo), presses every ``period_s``
(0.3 to 1.5 s), chooses the key by the nearest heading or by thresholds on the size of the wanted
turn (:func:`threshold_key`), now and then slips (``lapse``: a neighbouring key, or a look
without a press, so the old key is held one period more), stops for a moment and drives on
(``stop_go``), or cuts corners (``corner_m``: the teacher's route is aimed at farther ahead).
The zoo's persons also drive as people do whatever their pace: what is late is their reading of
the scene, not of the robot's own turn (``sees_turn``: a want seen ``reaction_s`` ago is turned by
how far the robot has turned since, so a late person does not overshoot every turn), and they do
not hold a key that drives into a wall just ahead (``reflex_m``: they look again at once, and
never press such a key). ``steady`` has neither, so ``--keys`` demos stay what they were.
Learning is judged across the zoo (the bench suite ``keys``), never on one person.

>>> from lfdfuse.control.command import DriveParams
>>> nearest_key(0.0, DriveParams()), nearest_key(0.5, DriveParams()), nearest_key(-2.0, DriveParams())
('i', 'u', 'l')
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, fields

import numpy as np

from lfdfuse.control.command import DriveParams, command_to_heading
from lfdfuse.control.safety import SafetyParams
from lfdfuse.log.writer import LogWriter
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.loop import GoalSource
from lfdfuse.sources.teleop.inputs import SCHEMA, TOPIC, Input, teleop_input
from lfdfuse.sources.teleop.keys import KeyState, press

#: the keys a person driving forward uses (teleop_twist_keyboard's forward half and turns in place)
FORWARD_KEYS: tuple[str, ...] = ("i", "u", "o", "j", "l")


CHOICES: tuple[str, ...] = ("nearest", "thresholds")


@dataclass(frozen=True)
class KeyboardParams:
    """How a keyboard person presses: one person model of the zoo (:data:`PERSONS`).

    The defaults are ``simulate --keys``'s person (``steady``); a parameter at its default adds
    no random draw, so that person's demos stay what they were.
    """

    period_s: float = 0.5  # mean time between presses
    jitter: float = 0.4  # each interval is period × U(1 − jitter, 1 + jitter)
    reaction_s: float = 0.2  # a press answers what the teacher wanted this long ago
    choice: str = "nearest"  # "nearest": the key whose heading is nearest; "thresholds": by the turn's size
    arc_deg: float = 20.0  # thresholds: a wanted turn beyond this is an arc (u/o) …
    spin_deg: float = 65.0  # … and beyond this a turn in place (j/l)
    lapse: float = 0.0  # chance a press slips: half a wrong (neighbouring) key, half a late one
    stop_go: float = 0.0  # chance a press is a stop (k) held for pause_s before driving on
    pause_s: float = 1.0
    corner_m: float = 0.0  # corners cut: the teacher's route is aimed at this much farther ahead
    #: sees the wall coming: never holds or presses a key that drives into a laser return this
    #: close ahead (m); a held key that would looks again at once (0: no such reflex)
    reflex_m: float = 0.0
    #: sees where the robot points now: a late want is turned by how far the robot turned since
    #: (what is late is the reading of the scene, not of the robot's own turn)
    sees_turn: bool = False

    def check(self) -> None:
        """Raise :class:`ValueError` naming the first parameter out of its range."""
        ok = {
            "period_s": self.period_s > 0 and math.isfinite(self.period_s),
            "jitter": 0.0 <= self.jitter < 1.0,
            "reaction_s": 0.0 <= self.reaction_s <= 5.0,
            "choice": self.choice in CHOICES,
            "arc_deg": 0.0 <= self.arc_deg <= self.spin_deg <= 180.0,
            "spin_deg": 0.0 <= self.spin_deg <= 180.0,
            "lapse": 0.0 <= self.lapse <= 1.0,
            "stop_go": 0.0 <= self.stop_go < 1.0,
            "pause_s": 0.0 <= self.pause_s <= 60.0 and math.isfinite(self.pause_s),
            "corner_m": 0.0 <= self.corner_m <= 10.0,
            "reflex_m": 0.0 <= self.reflex_m <= 5.0 and math.isfinite(self.reflex_m),
        }
        for name, good in ok.items():
            if not good:
                raise ValueError(f"person model: {name} = {getattr(self, name)!r} is out of range")

    def describe(self) -> str:
        """Every parameter as ``name=value`` (the demo's provenance ``person_model``)."""
        return " ".join(f"{f.name}={getattr(self, f.name)!r}" for f in fields(self))


#: how near a wall ahead the zoo's persons (but ``steady``) take their hand off a key driving into it (m)
REFLEX_M = 0.5

#: the zoo: named person models (``simulate --person NAME``), each a plausible way to drive by keys
PERSONS: dict[str, KeyboardParams] = {
    # simulate --keys's person: a key every 0.5 s, nearest heading, reacting in 0.2 s
    "steady": KeyboardParams(),
    # quick hands: a key every 0.3 s answering what is wanted now
    "prompt": KeyboardParams(period_s=0.3, reaction_s=0.0, reflex_m=REFLEX_M, sees_turn=True),
    # slow to react: answers what was wanted 0.6 s ago, a key every 0.8 s
    "late": KeyboardParams(period_s=0.8, reaction_s=0.6, reflex_m=REFLEX_M, sees_turn=True),
    # few, coarse keys: every 1.2 s, straight until the turn is large, turns in place only past 80°
    "coarse": KeyboardParams(
        period_s=1.2,
        reaction_s=0.3,
        choice="thresholds",
        arc_deg=30.0,
        spin_deg=80.0,
        reflex_m=REFLEX_M,
        sees_turn=True,
    ),
    # careless: one press in six a wrong or a late key
    "sloppy": KeyboardParams(period_s=0.6, reaction_s=0.3, lapse=0.16, reflex_m=REFLEX_M, sees_turn=True),
    # stops now and then (one press in eight) for a second to look, then drives on
    "stop-and-go": KeyboardParams(
        period_s=0.7, reaction_s=0.3, stop_go=0.12, pause_s=1.0, reflex_m=REFLEX_M, sees_turn=True
    ),
    # aims 2 m farther along the route than the teacher: turns early, cuts the inside of corners
    "corner-cutter": KeyboardParams(
        period_s=0.6, reaction_s=0.2, corner_m=2.0, reflex_m=REFLEX_M, sees_turn=True
    ),
}

#: the order the forward keys lie in, left to right: a wrong key is a neighbour of the right one
_SIDE_ORDER: tuple[str, ...] = ("j", "u", "i", "o", "l")


def key_headings(keys: KeyState, drive: DriveParams) -> dict[str, float]:
    """The heading (rad) each forward key's command stands for under the drive mapping."""
    out = {}
    for key in FORWARD_KEYS:
        v, w = press(keys, key, drive).state.command
        th, _ = command_to_heading(np.array(v), np.array(w), drive)
        out[key] = float(th)
    return out


def nearest_key(heading_rad: float, drive: DriveParams, keys: KeyState | None = None) -> str:
    """The forward key whose command points nearest ``heading_rad`` (robot frame, rad)."""
    table = key_headings(keys or KeyState(), drive)
    return min(table, key=lambda k: (abs(math.remainder(heading_rad - table[k], math.tau)), k))


def threshold_key(heading_rad: float, arc_deg: float, spin_deg: float) -> str:
    """The key a person choosing by the size of the wanted turn presses: straight below
    ``arc_deg``, an arc up to ``spin_deg``, a turn in place beyond (robot frame, rad; left > 0)."""
    turn = math.degrees(abs(math.remainder(heading_rad, math.tau)))
    left = heading_rad > 0
    if turn < arc_deg:
        return "i"
    if turn < spin_deg:
        return "u" if left else "o"
    return "j" if left else "l"


class KeyboardPerson:
    """A :class:`~lfdfuse.sim.loop.GoalSource` pressing the key nearest to what ``teacher`` wants."""

    def __init__(
        self,
        teacher: GoalSource,
        *,
        drive: DriveParams,
        dt_s: float,
        rng: np.random.Generator,
        params: KeyboardParams = KeyboardParams(),
        keys: KeyState = KeyState(),
        beam_angles_rad: np.ndarray | None = None,
    ) -> None:
        if not (params.period_s > 0 and math.isfinite(params.period_s)):
            raise ValueError("the key period must be a positive number of seconds")
        params.check()
        self.teacher, self.drive, self.dt_s, self.rng, self.p = teacher, drive, dt_s, rng, params
        self.state = keys
        self._headings = key_headings(keys, drive)
        if params.reflex_m > 0 and beam_angles_rad is None:
            raise ValueError("a person with a reflex needs the laser's beam angles")
        self._angles = beam_angles_rad
        self._wants: deque[float] = deque(maxlen=round(params.reaction_s / dt_s) + 1)
        self._thetas: deque[float] = deque(maxlen=round(params.reaction_s / dt_s) + 1)
        self._next_s = 0.0
        self.presses: list[tuple[int, Input, tuple[float, float]]] = []  # (tick, key, command) not yet logged
        self.count = 0

    @property
    def done(self) -> bool:
        return self.teacher.done

    @property
    def reached(self) -> list[tuple[str, int]]:
        return self.teacher.reached

    def command(self, obs: Observation) -> tuple[float, float]:
        v, w = self.teacher.command(obs)
        th, moving = command_to_heading(np.array(v), np.array(w), self.drive)
        self._wants.append(float(th) if bool(moving) else math.nan)
        if self.p.sees_turn:
            self._thetas.append(obs.pose.theta)
        t = obs.k * self.dt_s
        if self.teacher.done:
            if self.state.command != (0.0, 0.0):
                self._press("k", obs.k)
            return self.state.command
        ranges = obs.reading.ranges_m if self.p.reflex_m > 0 else None
        if t + 1e-9 >= self._next_s:
            self._next_s = t + self._decide(obs.k, ranges)
        elif ranges is not None and self._into_wall(self.state.command, ranges):
            # the held key drives into a wall just ahead: look again now, at what is wanted now
            now = self._wants[-1]
            self._press("k" if math.isnan(now) else self._nearest(now, self._free_keys(ranges)), obs.k)
        return self.state.command

    def _into_wall(self, command: tuple[float, float], ranges: np.ndarray) -> bool:
        """Whether ``command`` drives forward into a laser return within ``reflex_m`` ahead."""
        v, w = command
        if v <= 0.0:
            return False
        th, _ = command_to_heading(np.array(v), np.array(w), self.drive)
        return _blocked(float(th), ranges, self._angles, self.p.reflex_m)

    def _free_keys(self, ranges: np.ndarray) -> tuple[str, ...]:
        """The forward keys that do not drive into a wall just ahead (turns in place always)."""
        return tuple(
            k
            for k in FORWARD_KEYS
            if not _blocked(self._headings[k], ranges, self._angles, self.p.reflex_m) or k in ("j", "l")
        )

    def _decide(self, k: int, ranges: np.ndarray | None) -> float:
        """Press (or, slipping, not yet) the key for what was wanted ``reaction_s`` ago; the time
        until the next look."""
        p = self.p
        want = self._wants[0]
        if p.sees_turn:
            want = math.remainder(want - (self._thetas[-1] - self._thetas[0]), math.tau)
        free = FORWARD_KEYS if ranges is None else self._free_keys(ranges)
        key = "k" if math.isnan(want) else self._choose(want, free)
        extra = 0.0
        if p.stop_go > 0 and key != "k" and float(self.rng.uniform()) < p.stop_go:
            key, extra = "k", p.pause_s  # a stop, held a while, then drive on
        elif p.lapse > 0 and float(self.rng.uniform()) < p.lapse:
            if float(self.rng.uniform()) < 0.5:
                # late: this press is missed; the old key is held until the next look
                return p.period_s * float(self.rng.uniform(1.0 - p.jitter, 1.0 + p.jitter))
            key = self._neighbour(key)
        self._press(key, k)
        return extra + p.period_s * float(self.rng.uniform(1.0 - p.jitter, 1.0 + p.jitter))

    def _choose(self, heading: float, free: tuple[str, ...] = FORWARD_KEYS) -> str:
        if self.p.choice == "thresholds":
            key = threshold_key(heading, self.p.arc_deg, self.p.spin_deg)
            if key in free:
                return key
        return self._nearest(heading, free)

    def _neighbour(self, key: str) -> str:
        """A key beside ``key`` (the finger slips), or forward for a slipped stop."""
        if key not in _SIDE_ORDER:
            return "i"
        i = _SIDE_ORDER.index(key)
        options = [_SIDE_ORDER[j] for j in (i - 1, i + 1) if 0 <= j < len(_SIDE_ORDER)]
        return options[int(self.rng.integers(len(options)))]

    def _nearest(self, heading: float, keys: tuple[str, ...] = FORWARD_KEYS) -> str:
        h = self._headings
        return min(keys, key=lambda k: (abs(math.remainder(heading - h[k], math.tau)), k))

    def _press(self, key: str, k: int) -> None:
        self.state = press(self.state, key, self.drive).state
        self.presses.append((k, Input("key", key, "keyboard"), self.state.command))
        self.count += 1


def _blocked(heading_rad: float, ranges_m: np.ndarray, angles_rad: np.ndarray | None, ahead_m: float) -> bool:
    """Whether a laser return lies in the strip ``ahead_m`` long along ``heading_rad`` as wide as
    the safety reflex's (:class:`~lfdfuse.control.safety.SafetyParams`)."""
    if angles_rad is None:
        return False
    r = np.where(np.isfinite(ranges_m) & (ranges_m > 0), ranges_m, np.inf)
    d = angles_rad - heading_rad
    with np.errstate(invalid="ignore"):
        along = r * np.cos(d)
        lateral = np.abs(r * np.sin(d))
    return bool(((along > 0) & (along < ahead_m) & (lateral < SafetyParams().halfwidth_m)).any())


class PressRecorder:
    """A sink writing the person's presses on ``/teleop/input`` (as a teleop log has them)."""

    def __init__(self, log: LogWriter, person: KeyboardPerson) -> None:
        self.log, self.person = log, person
        log.add_topic(TOPIC, SCHEMA)

    def record(self, obs: Observation, command: tuple[float, float]) -> None:
        for k, inp, cmd in self.person.presses:
            self.log.write(
                TOPIC,
                obs.t_ns,
                teleop_input(
                    obs.t_ns,
                    inp,
                    effect="move" if cmd != (0.0, 0.0) else "stop",
                    command=cmd,
                    wall_s=k * self.person.dt_s,
                ),
            )
        self.person.presses.clear()
