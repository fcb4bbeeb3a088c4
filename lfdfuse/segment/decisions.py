"""Decision points: where the teacher left the route the learned fusion would have taken.

A goal segment's fusion weights reproduce *how* the teacher steered; they cannot know *where*
the teacher turned off toward a goal still out of view. A decision point is found by replaying
the segment's learned fusion over the demo: a run of steps where the demonstrated heading
leaves the fused heading by more than ``divergence_rad`` to one side, while the teacher really
turns that way (from any heading it held before: a turn right after a corner left), at an
opening on that side that is no corner (with ``skip_corners``: the way ahead closed and the
other side too — there was no other way to go). With ``junctions``, a turn of the teacher's
own off a corridor that goes on (the way ahead open at the opening's onset) is one too where no
divergence made one: there the fusion, replayed on the teacher's track, already turns with
the teacher (it sees the opening the teacher is turning into), though the robot driving on
would not. Each decision splits the goal segment into
*drive on to the n-th opening on that side* | *turn into it* | *the rest*, with landmarks the
robot recognises from its own sensors (:mod:`lfdfuse.behaviors.openings`): the opening's
side, shape and order (:class:`OpeningCue`), and the heading change — this share of the
teacher's whole turn, and no less than it less ``turn_margin_rad`` (a turn ended short leaves
the robot at the tip of the corner it turns round).

Step ``d`` (the opening's onset) is where the robot begins the turn, step ``e`` (the turn
landmark met) the first step after it, exactly as the runtime switches steps. The turn's
weights are learned from where the teacher began to turn away from the learned fusion, if
that was earlier (``begin``).

A turn whose opening the default sensor does not express as a decision (no onset near it, or
one met mid-sweep, whose shape rules the turn out) is looked at again with the track's ``short`` sensor, its
sectors held ``short_lag_m`` back: a spur a few metres past a corner, passed while the default
sectors still swing through the corner's turn. The decision then names that lag (``lag_m``) and
the runtime senses its landmarks with a sensor of that lag.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from lfdfuse.behaviors.openings import SIDES
from lfdfuse.behaviors.passing import PassParams
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.track import (
    LandmarkTrack,
    OpeningCue,
    distance_tolerance,
    is_corner,
    onset_near,
    opening_open_ahead,
    opening_order,
    runs,
    teacher_turns,
    turn_began,
)


@dataclass(frozen=True)
class DecisionParams:
    """What a decision point is, and how its landmarks are written.

    A decision is a divergence — the demo's heading leaves the fused one (both smoothed over
    ``smooth_steps``) by more than ``divergence_rad`` for ``min_steps`` steps and ``min_area`` in
    all — where the teacher really turned (``min_turn_rad``) at an opening met ``lookback`` steps
    before to ``lookahead`` after it. Its turn landmark is ``turn_share`` of the teacher's turn
    and no less than the largest less ``turn_margin_rad``, read ``settle_steps`` past the onset.
    ``junctions`` and ``short_lag_m`` add decisions no divergence made: a teacher's turn off a
    corridor that goes on, and a spur just past a corner (sensed with sectors held closer).

    Why these defaults: they were chosen on generated off-route worlds set apart for tuning and
    kept only where they held on held-apart ones. Every decision more is one more landmark
    the robot can miss, so the settings that find more of them (``max_gap`` 20, ``rise_steps``
    40, ``shape_steps`` 25, all sectors held 1.5 m back) complete fewer runs and stay off.
    ``shape`` is on: without it a corner is taken for the side opening the teacher turned into,
    and the ``ring-spur`` table of ``make bench`` suite ``offroute`` completes none of its starts.
    The rate these defaults reach, and the command that measures it: the README, "Goals off the
    route".
    """

    divergence_rad: float = math.radians(15.0)  # demo vs fused heading (smoothed): a different way
    smooth_steps: int = 5
    min_steps: int = 4  # that long (control periods), gaps of up to ``max_gap`` allowed
    min_area: float = 1.0  # and Σ|divergence| over the run (rad × steps) at least this
    #: runs of one sign this few steps apart are one divergence (20 joins a divergence that
    #: broke up while the teacher turned, the fused heading swinging as the BAC changed)
    max_gap: int = 3
    min_turn_rad: float = math.radians(45.0)  # the teacher really turned that way
    #: a turn a rollout left the teacher's path at (``forced``) may leave the held heading by
    #: this little, if the heading still rose ``min_turn_rad``: the sectors were held again
    #: while the teacher turned (a corner taken in two), and the held heading lags the turn
    blamed_turn_rad: float = math.radians(20.0)
    #: ... within this many steps past the divergence (40 finds a teacher who began to diverge
    #: early, at a spur just past a corner, and turned into it well after)
    rise_steps: int = 25
    lookback: int = 60  # the opening's onset at most this many steps before the divergence
    lookahead: int = 40  # or this many steps after it (the teacher began to turn early)
    turn_share: float = 0.8  # the turn landmark: this share of the teacher's turn
    turn_after_rad: float = math.radians(30.0)  # ... and this far beyond its turn at the onset
    min_angle_rad: float = math.radians(40.0)
    max_angle_rad: float = math.radians(150.0)
    #: an opening met within this distance of the sub-segment's start is no place passed on
    #: the way: the teacher turned where the previous goal left them (round at a target in a
    #: room). The decision is then the turn alone, from the start — counting openings seen
    #: while turning on the spot would not carry over to the robot
    at_start_m: float = 0.5
    began_rad: float = math.radians(8.0)  # the teacher's turn began where it left the held heading by this
    landmark: OpeningCue = OpeningCue.PASSED  # how the opening is recognised
    passing: PassParams = PassParams()
    #: DISTANCE: the tolerance is this share of the distance, at most half the way back to
    #: the previous onset on that side, at least ``within_min_m``
    within_share: float = 0.5
    within_min_m: float = 1.0
    #: a turn into a corner (the way ahead closed at the opening's onset, and the other side
    #: closed) is no decision: there was no other way
    skip_corners: bool = True
    #: the landmark names the opening's shape (the way ahead open or closed at its onset)
    shape: bool = True
    corner_other_steps: int = 25  # the other side open this many steps either side of the onset: a T
    #: the opening's shape is the way ahead at its onset or this many steps before it (25: a
    #: teacher who cut into the opening early saw the far wall at the onset, where the robot,
    #: driving on, sees the corridor go on; 0: at the onset)
    shape_steps: int = 0
    #: the turn landmark looks at the teacher's turn this many steps past the onset at least ...
    settle_steps: int = 60
    #: ... and asks for at least the largest turn less this (None: the share alone)
    turn_margin_rad: float | None = math.radians(15.0)
    #: the teacher's own turns off a corridor that goes on (the way ahead open at the onset of
    #: the opening on the turn's side) are decisions too where no divergence made one, however
    #: closely the learned fusion followed them on the demo: the fusion replayed on the
    #: teacher's track turns where the teacher already turns
    junctions: bool = True
    #: a teacher's turn with no onset near it on the default sensor (its sectors still swinging
    #: through the turn of a corner just before a spur) is looked for on the track's ``short``
    #: sensor, its sectors held this far back (None: not looked for); the landmarks of a
    #: decision found there name that lag, and the runtime senses them with it
    short_lag_m: float | None = 1.5
    #: an opening's order is counted at its first onset where the onset the decision is found
    #: at flickers at its edge (:func:`~lfdfuse.segment.track.opening_order`): on for a further
    #: demo or a correction (``estimate --subgoals`` with several demos); off for the first demo,
    #: whose tables stay what they were
    first_onset: bool = False


@dataclass(frozen=True)
class DecisionPoint:
    """A turn-off in goal segment ``segment``: from step ``onset`` to step ``turn_end``."""

    segment: int
    side: str
    onset: int
    turn_end: int
    nth: int  # the opening's order among onsets on that side since ``since``
    since: int  # first step of the sub-segment the opening is counted in
    odometry_m: float
    angle_rad: float
    divergence_rad: float  # mean |demo − fused| over the divergence: why it is a decision
    at_start: bool = False  # the turn alone, from ``since`` (no opening to drive on to)
    #: first step the turn's weights are learned from: the teacher's turn may begin before the
    #: opening's onset (they knew it was coming); learned from the onset, a turn already half
    #: done would teach the style's steering, not the turn
    begin: int = -1
    cue: OpeningCue = OpeningCue.ALL  # how the opening is recognised
    within_m: float | None = None  # DISTANCE: the tolerance on ``odometry_m``
    ahead_open: bool | None = None  # the opening's shape, when the landmark names it
    #: the landmarks are sensed with the sectors held this far back (None: the sensor's default)
    lag_m: float | None = None


def _largest_rise(x: np.ndarray) -> float:
    """The largest ``x[j] − x[i]`` with ``i ≤ j`` (0 for a falling series)."""
    return float(np.max(x - np.minimum.accumulate(x)))


def find_decisions(
    *,
    segments: tuple[GoalSegment, ...],
    demo: np.ndarray,
    informative: np.ndarray,
    fused: np.ndarray,
    track: LandmarkTrack,
    params: DecisionParams = DecisionParams(),
    forced: Sequence[int] = (),
    cues: Mapping[int, OpeningCue] | None = None,
    whole: Collection[int] = (),
) -> list[DecisionPoint]:
    """Decision points of the goal segments that end at a goal (a tour has no turn-off to learn).

    ``demo (N, 2)`` demonstrated vectors, ``fused (N, 2)`` the segment's learned fusion
    replayed on the same steps. ``forced``: steps within teacher's turns that are decisions
    whatever the fusion did and whatever the opening's shape (a rollout of the learned table
    left the teacher's path there: :mod:`lfdfuse.execute.repair`), unless one overlaps them.
    ``cues``: the landmark cue of the decision at that onset step, instead of ``params``'.
    ``whole``: onset steps of decisions whose turn landmark is the teacher's whole turn (no
    share, no margin short of it; the turn ended short left the robot facing the way back).
    """
    p = params
    plain = (
        find_decisions(
            segments=segments,
            demo=demo,
            informative=informative,
            fused=fused,
            track=track,
            params=replace(p, junctions=False),
        )
        if p.junctions or forced
        else []
    )
    hd = np.arctan2(demo[:, 1], demo[:, 0])
    hf = np.arctan2(fused[:, 1], fused[:, 0])
    valid = informative & (np.hypot(fused[:, 0], fused[:, 1]) > 1e-9)
    raw = np.where(valid, np.arctan2(np.sin(hd - hf), np.cos(hd - hf)), 0.0)
    k = max(p.smooth_steps, 1)
    err = np.convolve(raw, np.ones(k) / k, mode="same")
    out: list[DecisionPoint] = []
    for seg in segments:
        if seg.goal is None:
            continue
        since = seg.start
        lo, hi = seg.start, seg.stop
        e = err[lo:hi]
        mask = valid[lo:hi] & (np.abs(e) > p.divergence_rad)
        found = [
            (a + lo, b + lo, sgn, False)
            for a, b, sgn in runs(mask, np.sign(e), p.max_gap)
            if b - a >= p.min_steps and float(np.abs(e[a:b]).sum()) >= p.min_area
        ]
        if p.junctions or forced:  # the teacher's own turns (not the network's: a correction
            # log) where no divergence made a decision
            big = teacher_turns(track, lo, hi, began_rad=p.began_rad, min_turn_rad=p.min_turn_rad)
            small = (
                teacher_turns(track, lo, hi, began_rad=p.began_rad, min_turn_rad=p.blamed_turn_rad)
                if forced
                else big
            )
            found = sorted(
                found
                + [
                    (a, b, sgn, True)
                    for a, b, sgn in small
                    if b - a >= p.min_steps
                    and informative[a:b].mean() >= 0.5
                    and not any(d.segment == seg.index and a < d.turn_end and d.begin < b for d in plain)
                    and (any(a <= f < b for f in forced) or (p.junctions and (a, b, sgn) in big))
                ]
            )
        for a, b, sgn, own in found:
            must = own and any(a <= f < b for f in forced)
            if a < since:
                continue
            ref = max(a - p.lookback, since)
            turned = sgn * np.cumsum(track.turn_rad[ref + 1 : min(b + p.rise_steps, hi)])
            if not len(turned) or _largest_rise(turned) < p.min_turn_rad:
                continue  # the teacher did not really turn that way (from any heading it held before)
            turn = _Turn(seg.index, a, b, sgn, own, must, since, hi)
            views = [track] if p.short_lag_m is None or track.short is None else [track, track.short]
            # the default sectors first; where they sense no opening there that makes a decision
            # (still swinging through the turn of a corner just before a spur), sectors held a
            # shorter way back
            for tr in views:
                dp = _decision(tr, turn, p, cues, whole, float(np.abs(raw[a:b][valid[a:b]]).mean()))
                if dp is not None:
                    out.append(replace(dp, lag_m=None if tr is track else tr.params.lag_m))
                    since = dp.turn_end
                    break
    return out


@dataclass(frozen=True)
class _Turn:
    """A teacher's turn that may be a decision: steps ``[a, b)`` of goal segment ``segment``
    (its steps ``[.., hi)``) toward ``sgn``, in the sub-segment from ``since``."""

    segment: int
    a: int
    b: int
    sgn: float
    own: bool  # the teacher's own turn, found without a divergence
    must: bool  # a forced decision
    since: int
    hi: int


def _decision(
    tr: LandmarkTrack,
    t: _Turn,
    p: DecisionParams,
    cues: Mapping[int, OpeningCue] | None,
    whole: Collection[int],
    div: float,
) -> DecisionPoint | None:
    """The decision at turn ``t`` as the openings of ``tr`` express it, or None (no opening the
    robot could recognise there, or the turn was none to decide: see :func:`find_decisions`)."""
    a, b, sgn, own, must, since, hi = t.a, t.b, t.sgn, t.own, t.must, t.since, t.hi
    s = 0 if sgn > 0 else 1
    ref = max(a - p.lookback, since)
    d = onset_near(tr, s, ref, min(b + p.lookahead, hi), a, p.began_rad)
    if d is None:
        return None  # no opening the robot could recognise: not expressible as a landmark
    q = replace(p, landmark=cues[d]) if cues and d in cues else p
    odo = float(tr.step_m[since : d + 1].sum())
    at_start = odo < p.at_start_m
    if own and not must and (at_start or not opening_open_ahead(tr, d, since, p.shape_steps)):
        return None  # the teacher's own turn is a decision only off a way that goes on
    if (
        not at_start
        and not must
        and p.skip_corners
        and is_corner(tr, s, d, since, shape_steps=p.shape_steps, other_steps=p.corner_other_steps)
    ):
        return None  # a corner: the teacher turned where there was no other way
    nth = opening_order(tr, s, since, d, q.landmark, q.passing, first_onset=q.first_onset)
    within = (
        distance_tolerance(tr, s, since, d, odo, share=q.within_share, min_m=q.within_min_m)
        if q.landmark == OpeningCue.DISTANCE
        else None
    )
    if at_start:
        d = since  # the turn step is all of it: the robot turns where the goal left it
    if d in whole:  # keyed by the decision's onset as written
        q = replace(q, turn_share=1.0, turn_margin_rad=0.0)
    # the turn landmark counts from the heading the sectors were held at when the turn
    # step began (the heading before the turn, for teacher and robot alike, however
    # early either began to turn): this share of the teacher's largest turn from it
    heading = np.cumsum(tr.turn_rad)
    look = min(max(b + 25, d + q.settle_steps), hi)
    from_held = sgn * (heading[d:look] - heading[d] + tr.held_rad[d])
    # ... and at least ``turn_after_rad`` beyond where the teacher had turned at the onset
    # (met mid-turn, a share of the whole would leave the step a sliver of the turn), but
    # never beyond the teacher's whole turn
    want = max(q.turn_share * from_held.max(), min(from_held[0] + q.turn_after_rad, from_held.max()))
    if q.turn_margin_rad is not None:
        want = max(want, from_held.max() - q.turn_margin_rad)
    angle = float(np.clip(want, q.min_angle_rad, q.max_angle_rad))
    reach = np.nonzero(from_held[1:] >= angle)[0]
    end = d + 1 + int(reach[0]) if len(reach) else hi
    if must and end + p.min_steps >= hi:
        # the goal came while the teacher still turned: the turn as far as it went a
        # moment before the goal, the rest that moment; a goal beyond the turn's window (the
        # teacher turned less than a decision's least turn there): as far as it went in it
        end = min(hi - p.min_steps, look - 1)
        if end <= d + 1:
            return None
        angle = float(from_held[end - d])
        if angle < q.min_angle_rad:
            return None
    if end + 1 >= hi:
        return None  # the goal came first: nothing left to steer after the turn
    begin = turn_began(heading, tr.held_rad, d, max(since, d - p.lookback), sgn, p.began_rad)
    return DecisionPoint(
        t.segment,
        SIDES[s],
        d,
        end,
        nth,
        since,
        odo,
        angle,
        div,
        at_start,
        begin,
        OpeningCue(q.landmark),
        within,
        opening_open_ahead(tr, d, since, p.shape_steps) if p.shape and not at_start and not must else None,
    )


def split_segments(
    segments: tuple[GoalSegment, ...], decisions: list[DecisionPoint]
) -> list[tuple[int, GoalSegment]]:
    """Sub-segments ``(original segment index, sub-segment)`` in time order; only the last
    sub-segment of a goal segment keeps its goal. Indices are renumbered."""
    out: list[tuple[int, GoalSegment]] = []
    for seg in segments:
        cuts = [
            (d.begin if d.begin >= 0 else d.onset, d.turn_end) for d in decisions if d.segment == seg.index
        ]
        bounds = [seg.start]
        for d, e in cuts:
            bounds += [d, e]
        bounds.append(seg.stop)
        for j in range(len(bounds) - 1):
            last = j == len(bounds) - 2
            out.append(
                (seg.index, GoalSegment(len(out), bounds[j], bounds[j + 1], seg.goal if last else None))
            )
    return out
