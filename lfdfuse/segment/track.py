"""The demo's landmark cues, step by step: what a robot driving the demo's way would recognise
from its own sensors (:mod:`lfdfuse.behaviors.openings`) — openings met on either side, the
way ahead, odometry and the heading held through a turn — and the queries
:mod:`lfdfuse.segment.decisions` asks of them: where the teacher turned, the opening they turned
into, its shape and order, and how far it was driven to.

Only odometry increments and scans are used, as the robot has them at run time: a landmark
written from this track is one the runtime can meet.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import StrEnum

import numpy as np

from lfdfuse.behaviors.openings import (
    OpeningParams,
    ahead_range,
    odometry_increments,
    sensed_onsets,
    side_openings,
)
from lfdfuse.behaviors.passing import PassParams, passed_before
from lfdfuse.robot.readings import ScanGeometry


@dataclass(frozen=True)
class LandmarkTrack:
    """Landmark cues of every demo step: ``onsets (N, 2)`` (left, right), odometry ``(N,)``,
    and the scans ``(N, B)`` they came from."""

    onsets: np.ndarray
    step_m: np.ndarray
    turn_rad: np.ndarray
    held_rad: np.ndarray  # (N,) heading turned since the heading the sectors are held at (+ = left)
    ranges_m: np.ndarray
    geometry: ScanGeometry
    params: OpeningParams
    #: the same steps as a sensor with the sectors held a shorter way back sees them (None: not
    #: looked at): where a spur opens a few metres past a corner, the default sectors are still
    #: swinging through the corner's turn as the opening passes and sense no onset there
    short: LandmarkTrack | None = None


def landmark_track(
    ranges_m: np.ndarray,
    geometry: ScanGeometry,
    pose: np.ndarray,
    params: OpeningParams = OpeningParams(),
    *,
    short_lag_m: float | None = None,
) -> LandmarkTrack:
    """Cues from scans ``(N, B)`` and odometry poses ``(N, 3)`` (only their increments are used);
    with ``short_lag_m``, also as the sensor holding its sectors that far back sees them (``short``)."""
    step_m, turn = odometry_increments(pose)
    onsets, held = sensed_onsets(ranges_m, geometry, step_m, turn, params)
    short = (
        None
        if short_lag_m is None
        else landmark_track(ranges_m, geometry, pose, replace(params, lag_m=short_lag_m))
    )
    return LandmarkTrack(onsets, step_m, turn, held, np.asarray(ranges_m), geometry, params, short)


class OpeningCue(StrEnum):
    """How a decision's drive-on step recognises its opening: the alternatives measured on the
    generated off-route worlds."""

    #: the n-th onset on the side since the step began
    ALL = "all"
    #: the n-th opening on the side passed by, not turned into (:class:`PassedCounter`)
    PASSED = "passed"
    #: the first onset on the side once the teacher's distance less a tolerance has been driven
    DISTANCE = "distance"


def runs(mask: np.ndarray, sign: np.ndarray, max_gap: int) -> list[tuple[int, int, float]]:
    """Runs ``(start, stop, side sign)`` of ``mask`` with one sign, bridging short gaps."""
    out: list[tuple[int, int, float]] = []
    idx = np.nonzero(mask)[0]
    if not len(idx):
        return out
    a = b = int(idx[0])
    s = float(sign[a])
    for i in idx[1:].tolist():
        if i - b <= max_gap + 1 and float(sign[i]) == s:
            b = i
            continue
        out.append((a, b + 1, s))
        a = b = i
        s = float(sign[i])
    out.append((a, b + 1, s))
    return out


def teacher_turns(
    track: LandmarkTrack, lo: int, hi: int, *, began_rad: float, min_turn_rad: float
) -> list[tuple[int, int, float]]:
    """Runs ``(start, stop, side sign)`` in ``[lo, hi)`` where the teacher turned away from the
    held heading by more than ``began_rad``, reaching ``min_turn_rad``."""
    h = track.held_rad[lo:hi]
    out: list[tuple[int, int, float]] = []
    for sgn in (1.0, -1.0):
        off = sgn * h > began_rad
        for a, b, _ in runs(off, np.full(len(h), sgn), 0):
            if float((sgn * h[a:b]).max()) >= min_turn_rad:
                out.append((a + lo, b + lo, sgn))
    return out


def onset_near(track: LandmarkTrack, side: int, lo: int, hi: int, at: int, tol: float) -> int | None:
    """The first onset on ``side`` in ``[lo, hi)`` met while the teacher had turned toward that
    side by more than ``tol`` from the held heading (the opening they turned into: the robot,
    driving on, meets it there; a later onset as the teacher weaves out of the turn is one the
    robot may never see), else the onset nearest step ``at`` (the divergence's start).

    The sectors are held at the heading from before a turn (:class:`OpeningSensor`), so the
    onset is where a robot driving on with the style's weights meets the opening, though the
    teacher began to turn earlier.
    """
    hit = lo + np.nonzero(track.onsets[lo:hi, side])[0]
    if not len(hit):
        return None
    sgn = 1.0 if side == 0 else -1.0
    turning = hit[sgn * track.held_rad[hit] >= tol]
    if len(turning):
        return int(turning[0])
    return int(hit[np.argmin(np.abs(hit - at))])


def turn_began(heading: np.ndarray, held_rad: np.ndarray, d: int, lo: int, sgn: float, tol: float) -> int:
    """The first step of the teacher's turn toward ``sgn`` that is under way at step ``d``: the
    start of the run of steps in ``[lo, d]`` turned more than ``tol`` from ``d``'s held heading."""
    held = heading[d] - held_rad[d]
    off = sgn * (heading[lo : d + 1] - held) > tol
    if not off[-1]:
        return d
    before = np.nonzero(~off)[0]
    return lo + (int(before[-1]) + 1 if len(before) else 0)


def open_ahead(track: LandmarkTrack, d: int) -> bool:
    """At step ``d`` the way ahead, along the heading the sectors are held at, is open
    (:func:`ahead_range`, as the live sensor measures it)."""
    ahead = ahead_range(track.ranges_m[d], track.geometry, track.params, offset_rad=-track.held_rad[d])
    return ahead >= track.params.ahead_open_m


def opening_open_ahead(track: LandmarkTrack, d: int, since: int, shape_steps: int) -> bool:
    """The shape of the opening met at onset ``d``: the way ahead open at ``d`` or at any of the
    ``shape_steps`` before it (not before ``since``). Where the teacher cut into the opening, the
    far side of it closes the view at the onset; a robot driving on meets it with the way ahead
    open, as the teacher saw it a moment earlier. A corner is closed all along."""
    return any(open_ahead(track, i) for i in range(max(since, d - shape_steps), d + 1))


def is_corner(
    track: LandmarkTrack, side: int, d: int, since: int, *, shape_steps: int, other_steps: int
) -> bool:
    """At onset ``d``: the way ahead closed and the other side closed for ``other_steps`` around
    it — a corner, not a junction or a T."""
    if opening_open_ahead(track, d, since, shape_steps):
        return False
    lo, hi = max(d - other_steps, 0), min(d + other_steps + 1, len(track.held_rad))
    flags = side_openings(
        track.ranges_m[lo:hi], track.geometry, track.params, offset_rad=-track.held_rad[lo:hi]
    )
    return not bool(flags[:, 1 - side].any())


def opening_order(
    track: LandmarkTrack,
    side: int,
    since: int,
    d: int,
    cue: OpeningCue,
    passing: PassParams,
    *,
    first_onset: bool = False,
) -> int:
    """The order on its side since ``since`` of the opening met at ``d``, as ``cue`` counts it.

    ``first_onset``: an onset at ``d`` flickering at the edge of an opening met just before
    (within :attr:`PassParams.merge_m`) has that opening's order, counted at its first onset,
    whether it was passed by or is the one turned into (the runtime meets the opening at its
    first onset). Without it such an onset counts the openings passed before ``d``, one short
    where the opening met just before is the one the turn goes into."""
    if cue == OpeningCue.PASSED:
        lo = since + 1  # the runtime starts a step's count at the tick after the last was met
        if d < lo:
            return 1
        cut = slice(lo, d + 1)
        before, new = passed_before(
            track.onsets[cut], track.step_m[cut], track.turn_rad[cut], track.held_rad[cut], passing
        )
        if first_onset and not new[-1, side]:
            first = np.nonzero(new[:-1, side])[0]
            if len(first) and float(track.step_m[lo + int(first[-1]) + 1 : d + 1].sum()) <= passing.merge_m:
                return int(before[first[-1], side]) + 1
        # an onset flickering at the edge of an opening met just before is that opening; and
        # at least the first (where the opening met just before was turned into, not passed,
        # it counts nothing, and ``nth`` 0 is no landmark a table can hold)
        return max(1, int(before[-1, side]) + int(new[-1, side]))
    return int(track.onsets[since:d, side].sum()) + 1


def distance_tolerance(
    track: LandmarkTrack, side: int, since: int, d: int, odo: float, *, share: float, min_m: float
) -> float:
    """The tolerance on the distance ``odo`` driven to onset ``d``: a share of it, at most half
    the way back to the previous onset on that side since ``since`` (the robot must not take
    that one), at least ``min_m``."""
    prev = np.nonzero(track.onsets[since:d, side])[0]
    tol = share * odo
    if len(prev):
        gap = float(track.step_m[since + int(prev[-1]) + 1 : d + 1].sum())
        tol = min(tol, gap / 2)
    return max(tol, min_m)
