"""Sub-goals at decision points: landmark postconditions of a fusion step.

A person turns into a side corridor because they know the goal is there, long before the
camera sees it. The learned network reproduces that turn with two extra fusion steps inside
the goal's step: *drive on to the n-th opening on a side* (the style's weights) and *turn into
it* (the weights the teacher turned with), each ended by a landmark the robot recognises from
its own sensors — never map coordinates:

``{opening: left, nth: 2, odometry_m: 23.7, count: passed, ahead: open}``
    met at the onset of an opening on the left since the step began, once the robot has driven
    at least half of ``odometry_m`` (how far the teacher had driven by then; half, since
    distances change from building to building), that is

    - of the opening's *shape* ``ahead`` when given: the way ahead (along the heading the
      sectors are held at) still ``open`` — a side opening, a junction — or ``closed`` — a
      corner, the T at the end of a corridor. A corner the route turns round is never the
      side opening a teacher turned into. A side opening whose onset reads the way ahead
      closed (the robot veered toward it and sees its far wall) is the one if the way ahead
      reads open while the opening is still beside the robot;
    - the ``nth`` (or a later one) by ``count``: ``all`` onsets on that side (what a table without ``count`` means), or only the openings ``passed`` by, not turned
      into (:class:`lfdfuse.behaviors.passing.PassedCounter`). Corners met while turning
      come and go with the line each driver takes; counted, they made the robot take the
      opening before or after the teacher's from another start;
    - or, with ``within_m``, the first one once ``odometry_m − within_m`` has been driven,
      whatever came before (an alternative measured on the generated worlds, not written by ``estimate``);

    while a step ended by an ``ahead: open`` opening runs, the runtime keeps the fused heading
    within :data:`~lfdfuse.network.runtime.DRIVE_ON_RAD` of the held heading as long as the way
    ahead is open: the robot drives past the openings before the one to turn into;
``{turned: left, angle_rad: 1.2}``
    met once the robot has turned that far toward that side from its heading before the turn:
    the heading the opening sectors were held at when the step began (a robot that meets the
    opening driving straight and a teacher who began to turn early end the turn on the same
    heading). While it runs, the runtime never steers to the other side; after it, the next
    step keeps near the heading the turn ended on for a while
    (:data:`~lfdfuse.network.runtime.SETTLE_M`), into the corridor the turn faces.

Either may add ``lag_m: 1.5``: its openings and the heading its turn counts from are sensed with
the opening sectors held 1.5 m of travel back instead of the sensor's default 2 m
(:class:`~lfdfuse.behaviors.openings.OpeningSensor`; the runtime runs one sensor per lag a table
names). ``estimate`` writes it where the default sectors sensed no opening that makes the
teacher's turn a decision: a spur a few metres past a corner, met while the default sectors
still swing through the corner's turn.

:class:`Progress` is what a running step has sensed since it began; :meth:`Landmark.met`
decides from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, ClassVar

from lfdfuse.behaviors.openings import SIDES
from lfdfuse.behaviors.passing import PassedCounter
from lfdfuse.errors import ConfigError


@dataclass(frozen=True)
class Cues:
    """What the robot sensed this tick: opening onsets and odometry increments."""

    onset_left: bool = False
    onset_right: bool = False
    step_m: float = 0.0
    turn_rad: float = 0.0  # + = left
    held_turn_rad: float = 0.0  # turned since the heading the opening sectors are held at
    ahead_open: bool = True  # the way ahead, along that held heading, is open
    #: the opening met last on (left, right) is still beside the robot (its onset's tracker state)
    beside: tuple[bool, bool] = (False, False)
    front_open: bool = True  # the way ahead along the robot's own heading is open
    #: this tick as sensors holding their sectors another way back see it: ``(lag_m, cues)``
    #: for every lag a landmark of the table names (:attr:`Landmark.lag_m`)
    lagged: tuple[tuple[float, Cues], ...] = ()

    def seen_with(self, lag_m: float | None) -> Cues:
        """This tick as the sensor of a landmark sensed with ``lag_m`` sees it (None: the
        default sensor; so does a lag no sensor was built for, where nothing was sensed)."""
        if lag_m is None or not self.lagged:
            return self
        for lag, cues in self.lagged:
            if lag == lag_m:
                return cues
        raise ValueError(f"no opening sensor holds its sectors {lag_m} m back")


@dataclass
class Progress:
    """Openings met, distance driven and heading change since the active step began."""

    openings: list[int]  # onsets on (left, right)
    travelled_m: float = 0.0
    turned_rad: float = 0.0
    onset: tuple[bool, bool] = (False, False)  # at this tick
    ahead_open: bool = True  # at this tick
    #: heading change since the step began (rad, + = left)
    heading_rad: float = 0.0
    #: the step began where a turn ended: it keeps to the heading the turn ended on for a while
    #: (:data:`lfdfuse.network.runtime.SETTLE_M`)
    after_turn: bool = False
    #: openings passed by (not turned into) on each side before this tick
    passed: PassedCounter = field(default_factory=PassedCounter)
    #: per side: the opening beside the robot met every condition of the step's landmark at
    #: its onset but the way ahead being open (:meth:`Landmark.waits`)
    waiting: list[bool] = field(default_factory=lambda: [False, False])
    #: the openings are sensed with the sectors held this far back (None: the default sensor)
    lag_m: float | None = None

    @staticmethod
    def fresh(turned_rad: float = 0.0, lag_m: float | None = None) -> Progress:
        """Nothing passed yet; ``turned_rad`` already turned (from the held heading of the
        sensor with ``lag_m``)."""
        return Progress([0, 0], turned_rad=turned_rad, lag_m=lag_m)

    def add(self, cues: Cues) -> None:
        """This tick's cues, as the step's sensor sees them (:meth:`Cues.seen_with`)."""
        cues = cues.seen_with(self.lag_m)
        self.onset = (cues.onset_left, cues.onset_right)
        self.ahead_open = cues.ahead_open
        self.heading_rad += cues.turn_rad
        self.openings[0] += cues.onset_left
        self.openings[1] += cues.onset_right
        self.travelled_m += cues.step_m
        self.turned_rad += cues.turn_rad
        self.passed.update(self.onset, cues.step_m, cues.turn_rad, cues.held_turn_rad)
        self.waiting = [w and b for w, b in zip(self.waiting, cues.beside, strict=True)]


class Ahead(StrEnum):
    """The opening's shape, as the way ahead is at its onset."""

    #: the corridor goes on: a side opening, a junction
    OPEN = "open"
    #: it ends: a corner, or the T at the end of a corridor (or a dead end)
    CLOSED = "closed"


class OpeningCount(StrEnum):
    """Which openings an opening landmark's ``nth`` counts since its step began."""

    #: every onset on the side (a table without ``count`` means this)
    ALL = "all"
    #: openings passed by, not turned into (:class:`lfdfuse.behaviors.passing.PassedCounter`)
    PASSED = "passed"


@dataclass(frozen=True)
class Landmark:
    """A postcondition recognised from the robot's own sensors (see the module docstring)."""

    kind: str  # "opening" or "turned"
    side: str  # "left" or "right"
    nth: int = 1
    odometry_m: float | None = None
    angle_rad: float = 0.0
    count: OpeningCount = OpeningCount.ALL
    #: only an opening of this shape is the one (None: any)
    ahead: Ahead | None = None
    #: met at the first opening on the side once ``odometry_m − within_m`` has been driven (nth unused)
    within_m: float | None = None
    #: sensed with the opening sectors held this far back (m of travel; None: the sensor's
    #: default, :attr:`~lfdfuse.behaviors.openings.OpeningParams.lag_m`): a decision found where
    #: the default sectors were still swinging through the turn of a corner just before
    lag_m: float | None = None
    #: an opening matches only after this share of ``odometry_m`` has been driven
    ODOMETRY_SHARE: ClassVar[float] = 0.5

    @property
    def drives_on(self) -> bool:
        """A step ended by this landmark drives on along the corridor (the runtime keeps it near
        the held heading while the way ahead is open): the opening is a side opening."""
        return self.kind == "opening" and self.ahead == Ahead.OPEN

    def met(self, p: Progress) -> bool:
        s = SIDES.index(self.side)
        if self.kind == "opening":
            return self._opening(p, s)
        sign = 1.0 if self.side == "left" else -1.0
        return sign * p.turned_rad >= self.angle_rad

    def waits(self, p: Progress) -> int | None:
        """The side of this tick's onset when it is this ``ahead: open`` landmark's opening in
        all but the way ahead, which reads closed: a robot that veered toward the opening on its
        way to it (as the style, or the goal in view, pulls) sees the far wall of the opening
        along the held heading. The opening is the step's if the way ahead reads open while it
        is still beside the robot (:attr:`Progress.waiting`)."""
        if self.kind != "opening" or self.ahead != Ahead.OPEN:
            return None
        s = SIDES.index(self.side)
        if not p.onset[s] or p.ahead_open or not self._counted(p, s):
            return None
        return s

    def _opening(self, p: Progress, s: int) -> bool:
        """This tick's onset on side ``s`` is the step's opening, or the opening still beside
        the robot that waited for the way ahead to open."""
        if not p.onset[s]:
            return p.waiting[s] and p.ahead_open and self.ahead == Ahead.OPEN
        if self.ahead is not None and p.ahead_open != (self.ahead == Ahead.OPEN):
            return False
        return self._counted(p, s)

    def _counted(self, p: Progress, s: int) -> bool:
        """This tick's onset on side ``s`` is the one the landmark counts to (shape aside)."""
        if self.within_m is not None and self.odometry_m is not None:
            return p.travelled_m >= self.odometry_m - self.within_m
        far_enough = self.odometry_m is None or p.travelled_m >= self.ODOMETRY_SHARE * self.odometry_m
        if self.count == OpeningCount.PASSED:
            return p.passed.new[s] and p.passed.before[s] + 1 >= self.nth and far_enough
        return p.openings[s] >= self.nth and far_enough

    def describe(self) -> str:
        """One line a person reads: what the robot waits for."""
        if self.kind == "opening":
            odo = (
                f" (the teacher met it after {self.odometry_m:.1f} m)" if self.odometry_m is not None else ""
            )
            shape = {None: "opening", Ahead.OPEN: "side opening", Ahead.CLOSED: "opening where the way ends"}
            what = shape[self.ahead]
            if self.within_m is not None and self.odometry_m is not None:
                return (
                    f"the first {what} on the {self.side} after {self.odometry_m:.1f} ± {self.within_m:.1f} m"
                    f"{self._lag()}"
                )
            nth = {1: "1st", 2: "2nd", 3: "3rd"}.get(self.nth, f"{self.nth}th")
            passed = " (counting those passed by)" if self.count == OpeningCount.PASSED else ""
            return f"the {nth} {what} on the {self.side}{passed}{odo}{self._lag()}"
        return f"turned {math.degrees(self.angle_rad):.0f}° to the {self.side}{self._lag()}"

    def _lag(self) -> str:
        return "" if self.lag_m is None else f", sensed {self.lag_m:g} m back"

    def to_dict(self) -> dict[str, Any]:
        if self.kind == "opening":
            d: dict[str, Any] = {"opening": self.side, "nth": self.nth}
            if self.odometry_m is not None:
                d["odometry_m"] = round(self.odometry_m, 2)
            if self.count != OpeningCount.ALL:
                d["count"] = str(self.count)
            if self.ahead is not None:
                d["ahead"] = str(self.ahead)
            if self.within_m is not None:
                d["within_m"] = round(self.within_m, 2)
        else:
            d = {"turned": self.side, "angle_rad": round(self.angle_rad, 3)}
        if self.lag_m is not None:
            d["lag_m"] = round(self.lag_m, 3)
        return d

    @staticmethod
    def from_dict(d: Any, where: str) -> Landmark:
        if not isinstance(d, dict):
            raise ConfigError(f"fusion table: {where} must be a mapping")
        kinds = [k for k in ("opening", "turned") if k in d]
        if len(kinds) != 1:
            raise ConfigError(f"fusion table: {where}: give exactly one of 'opening' or 'turned'")
        kind = kinds[0]
        allowed = (
            {"opening", "nth", "odometry_m", "count", "within_m", "ahead", "lag_m"}
            if kind == "opening"
            else {"turned", "angle_rad", "lag_m"}
        )
        bad = sorted(set(d) - allowed)
        if bad:
            raise ConfigError(
                f"fusion table: {where}: unknown field {bad[0]!r} (valid: {', '.join(sorted(allowed))})"
            )
        side = d[kind]
        if side not in SIDES:
            raise ConfigError(f"fusion table: {where}.{kind} must be 'left' or 'right'")
        lag = d.get("lag_m")
        if lag is not None and (
            isinstance(lag, bool) or not isinstance(lag, (int, float)) or not 0 < lag <= 10
        ):
            raise ConfigError(f"fusion table: {where}.lag_m must be a distance in (0, 10] metres")
        lag_m = None if lag is None else float(lag)
        if kind == "opening":
            nth = d.get("nth", 1)
            if isinstance(nth, bool) or not isinstance(nth, int) or not 1 <= nth <= 1000:
                raise ConfigError(f"fusion table: {where}.nth must be an integer in [1, 1000]")
            odo = d.get("odometry_m")
            if odo is not None and (
                isinstance(odo, bool) or not isinstance(odo, (int, float)) or not 0 <= odo < 1e6
            ):
                raise ConfigError(f"fusion table: {where}.odometry_m must be a distance in metres")
            count = d.get("count", "all")
            if count not in set(OpeningCount):
                raise ConfigError(f"fusion table: {where}.count must be 'all' or 'passed'")
            within = d.get("within_m")
            if within is not None and (
                isinstance(within, bool) or not isinstance(within, (int, float)) or not 0 <= within < 1e6
            ):
                raise ConfigError(f"fusion table: {where}.within_m must be a distance in metres")
            ahead = d.get("ahead")
            if ahead is not None and ahead not in set(Ahead):
                raise ConfigError(f"fusion table: {where}.ahead must be 'open' or 'closed'")
            if within is not None and odo is None:
                raise ConfigError(f"fusion table: {where}.within_m needs odometry_m")
            return Landmark(
                "opening",
                side,
                nth,
                None if odo is None else float(odo),
                count=OpeningCount(count),
                ahead=None if ahead is None else Ahead(ahead),
                within_m=None if within is None else float(within),
                lag_m=lag_m,
            )
        ang = d.get("angle_rad")
        if isinstance(ang, bool) or not isinstance(ang, (int, float)) or not 0 < ang <= 2 * math.pi:
            raise ConfigError(f"fusion table: {where}.angle_rad must be in (0, 2π]")
        return Landmark("turned", side, angle_rad=float(ang), lag_m=lag_m)
