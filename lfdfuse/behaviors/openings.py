"""Landmarks a robot recognises from its own sensors: side openings and odometry.

A purely reactive network cannot know *where* a person turned off the route. What it can
sense, without a map: an *opening* on its left or right (a junction, a door: most beams of a
side sector reach far), and how far it drove and how much it turned since some event
(odometry). The same code runs over a whole log (segmentation) and one scan at a time
(execution), so what the demo saw is what the robot will see.

* :func:`side_openings` — ``(N, B)`` scans → ``(N, 2)`` open flags (left, right).
* :class:`OpeningTracker` — open flags → *onsets* with hysteresis (an opening is entered once,
  however the beams flicker at its edges); :func:`opening_onsets` runs it over a log.
* :class:`OpeningSensor` — scans and odometry → onsets, with the side sectors held at the
  heading the robot had ``lag_m`` metres of travel ago while it was in a corridor there (in a
  room they turn with the robot); :func:`sensed_onsets` runs it over a log. This is what
  segmentation and execution both use.
* :class:`~lfdfuse.behaviors.passing.PassedCounter` (in :mod:`lfdfuse.behaviors.passing`) —
  onsets → openings passed by on each side (not turned into: a corner the route follows, a
  turn-off); :func:`~lfdfuse.behaviors.passing.passed_before` runs it over a log.
* :func:`odometry_increments` — ``(N, 3)`` poses → distance (m) and signed heading change
  (rad) per step: relative motion only, as wheel odometry gives it.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from lfdfuse.behaviors import kernels
from lfdfuse.robot.readings import ScanGeometry

LEFT, RIGHT = 0, 1
SIDES = ("left", "right")


@dataclass(frozen=True)
class OpeningParams:
    """What counts as an opening on a side (metres, radians, control periods)."""

    inner_rad: float = math.radians(60.0)  # the side sector spans these bearings from straight ahead
    outer_rad: float = math.radians(120.0)
    open_m: float = 3.0  # a beam this long passes into the opening (corridors here are ≤ 2.6 m wide)
    fraction: float = 0.5  # this share of the sector's beams must be that long
    on_ticks: int = 2  # open this many ticks in a row: entered
    off_ticks: int = 4  # closed this many ticks in a row: left behind
    #: openings count only while driving steadily: turning by more than this over the last
    #: ``steady_ticks`` (turning round in a dead end, into a corridor) sweeps the sectors
    #: over openings that are not junctions passed
    steady_rad: float = math.radians(25.0)
    steady_ticks: int = 8
    #: the sectors look from the heading the robot had this far back along its path. A teacher
    #: who knows the way cuts a corner and turns into a side corridor before the opening is
    #: abeam; a robot driving on with the style's weights meets it abeam. Held to the heading
    #: from before the turn, both see the same openings (corners included), so the order of an
    #: opening counted in the demo is the order the robot counts
    lag_m: float = 2.0
    #: the held sectors do not turn with the robot, so turning on the spot (round in a dead
    #: end, in a room) would look steady: turning more than this over the last ``spin_m`` of
    #: travel reads as closed too (a corner, even cut short, turns far less per metre)
    spin_rad: float = math.radians(45.0)
    spin_m: float = 0.5
    #: the sectors are held only where the robot was in a corridor (the beams abeam, left plus
    #: right, span at most ``open_m``) somewhere in the stretch from ``lag_m + corridor_back_m``
    #: to ``lag_m - corridor_ahead_m`` of travel ago. In a room (wider than ``open_m``) the
    #: robot turns round on the spot and the teacher turns where a target left them: there the
    #: sectors turn with the robot, and the tracker's steadiness is the robot's own
    corridor_back_m: float = 1.0
    corridor_ahead_m: float = 0.5
    corridor_beam_rad: float = math.radians(10.0)
    #: the way ahead (along the held heading, the beams within ``ahead_beam_rad`` of it) is
    #: open past this; closed nearer, an opening is a corner or the T at a corridor's end
    ahead_open_m: float = 4.0
    ahead_beam_rad: float = math.radians(10.0)


def ahead_range(
    ranges_m: np.ndarray, geometry: ScanGeometry, params: OpeningParams, *, offset_rad: float = 0.0
) -> float:
    """How far the way ahead is open (m) in a scan ``(B,)``: the median of the beams within
    ``ahead_beam_rad`` of the heading ``offset_rad`` from the robot's (+ = left; the sectors'
    held heading); a beam with no return reaches far. Inf for a scanner that does not look there.

    Compiled where it can be (:data:`~lfdfuse.behaviors.kernels.AHEAD`, the same number);
    :func:`ahead_range_reference` is the numpy."""
    if not kernels.AHEAD.ready():
        return ahead_range_reference(ranges_m, geometry, params, offset_rad=offset_rad)
    a = ahead_bearings(geometry) if offset_rad == 0.0 else _wrap(geometry.angles - offset_rad)
    return float(kernels.AHEAD(np.asarray(ranges_m, dtype=np.float64), a, params.ahead_beam_rad))


def _wrap(a: np.ndarray) -> np.ndarray:
    return np.asarray(np.arctan2(np.sin(a), np.cos(a)))


@lru_cache(maxsize=16)
def ahead_bearings(geometry: ScanGeometry) -> np.ndarray:
    """The bearings :func:`ahead_range_reference` looks along with no offset (``angles − 0``, wrapped)."""
    a = _wrap(geometry.angles - 0.0)
    a.flags.writeable = False
    return a


@lru_cache(maxsize=16)
def _side_bearings(geometry: ScanGeometry) -> np.ndarray:
    """The bearings :func:`side_openings_reference` looks along with a zero offset (wrapped twice)."""
    a = _wrap(_bearings(geometry) - 0.0)
    a.flags.writeable = False
    return a


@lru_cache(maxsize=16)
def _wrapped(geometry: ScanGeometry) -> bool:
    """Whether the layout's angles are their own wrapped bearings, bit for bit (then one wrap
    serves both the side sectors and the way ahead)."""
    return bool(np.array_equal(_bearings(geometry), geometry.angles))


def ahead_range_reference(
    ranges_m: np.ndarray, geometry: ScanGeometry, params: OpeningParams, *, offset_rad: float = 0.0
) -> float:
    """:func:`ahead_range` in numpy: the reference."""
    a = geometry.angles - offset_rad
    a = np.arctan2(np.sin(a), np.cos(a))
    r = np.asarray(ranges_m, dtype=np.float64)[np.abs(a) <= params.ahead_beam_rad]
    if not len(r):
        return math.inf
    return median(np.where(np.isfinite(r) & (r > 0.0), r, np.inf))


def median(x: np.ndarray) -> float:
    """``np.median`` of a non-empty 1-D array without NaN, the same number at a fraction of the
    cost on the few beams of a sector (the mean of the middle two is ``(a + b) / 2`` in both)."""
    s = np.sort(x)
    k = len(s) // 2
    return float(s[k]) if len(s) % 2 else float((s[k - 1] + s[k]) / 2.0)


@lru_cache(maxsize=16)
def _bearings(geometry: ScanGeometry) -> np.ndarray:
    """The beams' bearings wrapped into (−π, π] (read-only, once per layout)."""
    a = np.asarray(np.arctan2(np.sin(geometry.angles), np.cos(geometry.angles)))
    a.flags.writeable = False
    return a


def side_openings(
    ranges_m: np.ndarray,
    geometry: ScanGeometry,
    params: OpeningParams,
    *,
    offset_rad: np.ndarray | None = None,
) -> np.ndarray:
    """``(N, 2)`` bool: is there an opening on the left / right, per scan ``(N, B)``.

    A beam with no return (inf, NaN, ≤ 0 or at max range) reaches far. A scanner that does not
    cover a side sector never sees an opening there. ``offset_rad (N,)`` turns the sectors of
    each scan by that angle (+ = left): sectors fixed to an earlier heading, for a robot that
    has already begun to turn.

    Compiled where it can be (:data:`~lfdfuse.behaviors.kernels.SIDE_OPEN`, the same flags);
    :func:`side_openings_reference` is the numpy.
    """
    if not kernels.SIDE_OPEN.ready():
        return side_openings_reference(ranges_m, geometry, params, offset_rad=offset_rad)
    r = np.atleast_2d(np.asarray(ranges_m, dtype=np.float64))
    a = _bearings(geometry)[None, :]
    if offset_rad is not None:
        a = _wrap(a - np.asarray(offset_rad, dtype=np.float64).reshape(-1, 1))
    out = np.zeros((r.shape[0], 2), dtype=bool)
    far_m = min(params.open_m, geometry.max_range_m)
    kernels.SIDE_OPEN(r, a, far_m, params.inner_rad, params.outer_rad, params.fraction, out)
    return out


def side_openings_reference(
    ranges_m: np.ndarray,
    geometry: ScanGeometry,
    params: OpeningParams,
    *,
    offset_rad: np.ndarray | None = None,
) -> np.ndarray:
    """:func:`side_openings` in numpy: the reference."""
    r = np.atleast_2d(np.asarray(ranges_m, dtype=np.float64))
    a = _bearings(geometry)[None, :]
    if offset_rad is not None:
        a = a - np.asarray(offset_rad, dtype=np.float64).reshape(-1, 1)
        a = np.arctan2(np.sin(a), np.cos(a))
    far = ~np.isfinite(r) | (r <= 0.0) | (r >= min(params.open_m, geometry.max_range_m))
    out = np.zeros((r.shape[0], 2), dtype=bool)
    for side, sign in ((LEFT, 1.0), (RIGHT, -1.0)):
        sector = np.broadcast_to((sign * a >= params.inner_rad) & (sign * a <= params.outer_rad), r.shape)
        count = sector.sum(axis=1)
        share = np.divide((far & sector).sum(axis=1), count, out=np.zeros(len(r)), where=count > 0)
        out[:, side] = (count > 0) & (share >= params.fraction)
    return out


class OpeningTracker:
    """Turns per-tick open flags into onsets, with hysteresis (one tick at a time)."""

    def __init__(self, params: OpeningParams = OpeningParams()) -> None:
        self.params = params
        self.inside = [False, False]
        self._run = [0, 0]  # ticks the flag has disagreed with ``inside``
        self._turns: deque[float] = deque(maxlen=params.steady_ticks)

    def update(self, open_now: np.ndarray | tuple[bool, bool], turn_rad: float = 0.0) -> tuple[bool, bool]:
        """Onset (left, right) at this tick from its open flags ``(2,)`` and this tick's
        heading change (rad); while turning, the sides read as closed."""
        self._turns.append(turn_rad)
        steady = abs(sum(self._turns)) <= self.params.steady_rad
        onset = [False, False]
        for s in (LEFT, RIGHT):
            if (bool(open_now[s]) and steady) != self.inside[s]:
                self._run[s] += 1
                need = self.params.off_ticks if self.inside[s] else self.params.on_ticks
                if self._run[s] >= need:
                    self.inside[s] = not self.inside[s]
                    self._run[s] = 0
                    onset[s] = self.inside[s]
            else:
                self._run[s] = 0
        return onset[0], onset[1]


class OpeningSensor:
    """Onsets (left, right) from one scan and one odometry increment at a time.

    The side sectors are turned to the heading of ``params.lag_m`` of travel ago (an in-place
    turn does not move them until the robot drives on); the tracker's steadiness is that of
    this held heading, so sectors swept as it catches up after a turn count no opening.
    Only in corridors, though (:attr:`holding`): where the robot was in a room ``lag_m`` ago
    the sectors turn with it, and turning there reads as turning.
    """

    def __init__(self, geometry: ScanGeometry, params: OpeningParams = OpeningParams()) -> None:
        self.geometry = geometry
        self.params = params
        self.tracker = OpeningTracker(params)
        self._odo_m = 0.0
        self._heading = 0.0  # unwrapped, from the first tick
        self._held = 0.0
        self._path: deque[tuple[float, float]] = deque([(0.0, 0.0)])  # (odometry, heading)
        self._corridor: deque[tuple[float, bool]] = deque()  # (odometry, in a corridor)
        a = np.arctan2(np.sin(geometry.angles), np.cos(geometry.angles))
        self._abeam = (
            np.abs(a - math.pi / 2) <= params.corridor_beam_rad,
            np.abs(a + math.pi / 2) <= params.corridor_beam_rad,
        )
        self._abeam_at = (np.flatnonzero(self._abeam[0]), np.flatnonzero(self._abeam[1]))
        # what every tick of the compiled sensing reads of the layout, looked up once
        self._bear = _bearings(geometry)
        self._side0, self._ahead0 = _side_bearings(geometry), ahead_bearings(geometry)
        self._one_wrap = _wrapped(geometry)
        self._far_m = min(params.open_m, geometry.max_range_m)
        #: the sectors are held now (the robot was in a corridor ``lag_m`` ago)
        self.holding = False
        #: how far the robot has turned (rad, + = left) from the heading the sectors are held at
        self.held_turn_rad = 0.0
        #: how far the way ahead, along the held heading, is open (m) at this tick
        self.ahead_m = math.inf
        #: every distance so far ≥ 0 and the heading a number: the odometry along the deques
        #: never decreases (their scans may stop where it passes a bound), and the headings'
        #: spread is the same in any order
        self._ordered = True

    def update(self, ranges_m: np.ndarray, step_m: float, turn_rad: float) -> tuple[bool, bool]:
        """Onsets at this tick from its scan ``(B,)`` and odometry increment (m, rad)."""
        self._odo_m += step_m
        self._heading += turn_rad
        if not (step_m >= 0.0 and self._heading == self._heading):
            self._ordered = False
        self._path.append((self._odo_m, self._heading))
        while len(self._path) > 1 and self._path[1][0] <= self._odo_m - self.params.lag_m:
            self._path.popleft()
        ranges = np.asarray(ranges_m, dtype=np.float64)
        compiled = kernels.HELD.ready() and kernels.CORRIDOR.ready()
        self._corridor.append((self._odo_m, self._in_corridor(ranges, compiled)))
        back = self._odo_m - self.params.lag_m - self.params.corridor_back_m
        while len(self._corridor) > 1 and self._corridor[1][0] <= back:
            self._corridor.popleft()
        ahead = self._odo_m - self.params.lag_m + self.params.corridor_ahead_m
        if self._ordered:
            # any corridor tick up to ``ahead``: the odometry never decreases along the deque,
            # so those ticks are its head, and the first corridor tick there decides
            self.holding = False
            for odo, c in self._corridor:
                if odo > ahead:
                    break
                if c:
                    self.holding = True
                    break
        else:
            self.holding = any(c for odo, c in self._corridor if odo <= ahead)
        held = self._path[0][1] if self.holding else self._heading
        held_turn, self._held = held - self._held, held
        self.held_turn_rad = self._heading - held
        flags: np.ndarray | tuple[bool, bool]
        if compiled:
            flags, self.ahead_m = self._compiled(ranges, held - self._heading)
        else:
            flags = side_openings_reference(
                ranges[None, :], self.geometry, self.params, offset_rad=np.array([held - self._heading])
            )[0]
            self.ahead_m = ahead_range_reference(
                ranges, self.geometry, self.params, offset_rad=held - self._heading
            )
        if self.holding and self._spinning():
            flags = (False, False)
        return self.tracker.update(flags, held_turn)

    def _compiled(self, ranges: np.ndarray, offset: float) -> tuple[tuple[bool, bool], float]:
        """The open flags and the way ahead of :meth:`update` by the compiled loops (one call of
        :data:`~lfdfuse.behaviors.kernels.HELD`): the same bearings as the references wrap
        (once, where the layout's are already wrapped)."""
        g, p = self.geometry, self.params
        if offset == 0.0:
            side, ahead = self._side0, self._ahead0
        else:
            side = _wrap(self._bear - offset)
            ahead = side if self._one_wrap else _wrap(g.angles - offset)
        left, right, ahead_m = kernels.HELD(
            ranges, side, ahead, self._far_m, p.inner_rad, p.outer_rad, p.fraction, p.ahead_beam_rad
        )
        return (bool(left), bool(right)), float(ahead_m)

    def _in_corridor(self, ranges: np.ndarray, compiled: bool = False) -> bool:
        """Walls abeam on both sides, at most ``open_m`` apart (a beam with no return is far)."""
        if compiled:
            return bool(kernels.CORRIDOR(ranges, *self._abeam_at, self.params.open_m))
        r = np.where(np.isfinite(ranges) & (ranges > 0.0), ranges, np.inf)
        left, right = r[self._abeam[0]], r[self._abeam[1]]
        if not len(left) or not len(right):
            return False
        return median(left) + median(right) <= self.params.open_m

    def _spinning(self) -> bool:
        """Turned more than ``spin_rad`` over the last ``spin_m`` of travel."""
        since = self._odo_m - self.params.spin_m
        if not self._ordered:
            lo = min((h for odo, h in self._path if odo >= since), default=self._heading)
            hi = max((h for odo, h in self._path if odo >= since), default=self._heading)
            return hi - lo > self.params.spin_rad
        # the headings of the path since ``since``: its tail (the odometry never decreases),
        # read back from the newest; their spread is that of the whole tail, whatever the order
        low: float | None = None
        high: float | None = None
        for odo, h in reversed(self._path):
            if odo < since:
                break
            if low is None or h < low:
                low = h
            if high is None or h > high:
                high = h
        if low is None or high is None:
            low = high = self._heading  # nothing since: the heading less itself
        return high - low > self.params.spin_rad


def sensed_onsets(
    ranges_m: np.ndarray,
    geometry: ScanGeometry,
    step_m: np.ndarray,
    turn_rad: np.ndarray,
    params: OpeningParams = OpeningParams(),
) -> tuple[np.ndarray, np.ndarray]:
    """``(N, 2)`` bool onsets and ``(N,)`` :attr:`OpeningSensor.held_turn_rad` from scans
    ``(N, B)`` and odometry increments ``(N,)``, exactly as the live sensor sees them."""
    sensor = OpeningSensor(geometry, params)
    r = np.atleast_2d(np.asarray(ranges_m, dtype=np.float64))
    onsets = np.zeros((len(r), 2), dtype=bool)
    held = np.zeros(len(r))
    for i in range(len(r)):
        onsets[i] = sensor.update(r[i], float(step_m[i]), float(turn_rad[i]))
        held[i] = sensor.held_turn_rad
    return onsets, held


def opening_onsets(
    open_flags: np.ndarray, turn_rad: np.ndarray, params: OpeningParams = OpeningParams()
) -> np.ndarray:
    """``(N, 2)`` bool onsets from ``(N, 2)`` open flags and ``(N,)`` heading changes,
    exactly as the live tracker sees them."""
    tr = OpeningTracker(params)
    return np.array(
        [tr.update(f, float(w)) for f, w in zip(open_flags, turn_rad, strict=True)], dtype=bool
    ).reshape(-1, 2)


def odometry_increments(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance (m) and signed heading change (rad, + = left) of each step ``(N,)``; 0 for the first."""
    p = np.asarray(pose, dtype=np.float64).reshape(-1, 3)
    dist = np.zeros(len(p))
    turn = np.zeros(len(p))
    if len(p) > 1:
        dist[1:] = np.hypot(np.diff(p[:, 0]), np.diff(p[:, 1]))
        d = np.diff(p[:, 2])
        turn[1:] = np.arctan2(np.sin(d), np.cos(d))
    return dist, turn
