"""Decision points: found where the teacher turned off at an opening, never where the fusion agrees;
splitting tiles each goal segment."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from lfdfuse.behaviors.openings import OpeningParams
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.segment.decisions import DecisionParams, DecisionPoint, find_decisions, split_segments
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.track import LandmarkTrack, OpeningCue, opening_order, runs

N = 120
GEOM = ScanGeometry(-math.pi / 2, math.pi / 2, 3, 8.0)


def _turn_off(side: int = 0, onset_at: int | None = 38) -> tuple[np.ndarray, np.ndarray, LandmarkTrack]:
    """Straight on, then from step 40 the teacher turns 90° toward ``side`` over 20 steps while the
    learned fusion would drive on; an opening on that side begins at ``onset_at``."""
    sgn = 1.0 if side == 0 else -1.0
    turn = np.zeros(N)
    turn[40:60] = sgn * math.radians(90.0) / 20
    demo_heading = np.where((np.arange(N) >= 40) & (np.arange(N) < 60), sgn * math.radians(60.0), 0.0)
    demo = np.stack([np.cos(demo_heading), np.sin(demo_heading)], axis=1)
    fused = np.tile([1.0, 0.0], (N, 1))
    onsets = np.zeros((N, 2), dtype=bool)
    if onset_at is not None:
        onsets[onset_at, side] = True
    heading = np.cumsum(turn)
    held = np.where(
        np.arange(N) >= 40, heading - heading[39], 0.0
    )  # sectors held at the heading before the turn
    track = LandmarkTrack(onsets, np.full(N, 0.04), turn, held, np.full((N, 3), 8.0), GEOM, OpeningParams())
    return demo, fused, track


SEGS = (GoalSegment(0, 0, N, "attract_red"),)


def test_a_turn_off_at_an_opening_is_one_decision_on_that_side() -> None:
    for side, name in ((0, "left"), (1, "right")):
        demo, fused, track = _turn_off(side)
        (d,) = find_decisions(
            segments=SEGS, demo=demo, informative=np.ones(N, bool), fused=fused, track=track
        )
        assert d.side == name and d.segment == 0 and d.nth == 1 and d.since == 0
        assert 38 <= d.onset < d.turn_end < N
        assert 0 <= d.begin <= d.onset
        assert d.divergence_rad > math.radians(15)


def test_no_decision_where_the_fusion_agrees_without_an_opening_or_without_a_goal() -> None:
    demo, fused, track = _turn_off()
    ok = np.ones(N, bool)
    only = DecisionParams(junctions=False)  # the teacher's own turns at junctions: the law below
    assert (
        find_decisions(segments=SEGS, demo=demo, informative=ok, fused=demo, track=track, params=only) == []
    )
    _, _, blind = _turn_off(onset_at=None)
    assert find_decisions(segments=SEGS, demo=demo, informative=ok, fused=fused, track=blind) == []
    tour = (GoalSegment(0, 0, N, None),)
    assert find_decisions(segments=tour, demo=demo, informative=ok, fused=fused, track=track) == []
    # steps without heading information cannot diverge
    assert find_decisions(segments=SEGS, demo=demo, informative=~ok, fused=fused, track=track) == []


@settings(max_examples=40)
@given(st.lists(st.booleans(), max_size=60), st.integers(0, 4), st.integers(0, 2**32 - 1))
def test_runs_cover_the_mask_with_one_sign_each_bridging_short_gaps(
    mask_list: list[bool], max_gap: int, seed: int
) -> None:
    mask = np.array(mask_list, dtype=bool)
    sign = np.random.default_rng(seed).choice([-1.0, 1.0], size=len(mask))
    found = runs(mask, sign, max_gap)
    covered = np.zeros(len(mask), bool)
    last_stop = -1
    for a, b, s in found:
        assert last_stop <= a < b
        last_stop = b
        inside = np.nonzero(mask[a:b])[0] + a
        assert mask[a] and mask[b - 1]
        assert (sign[inside] == s).all()
        assert (np.diff(inside) <= max_gap + 1).all()
        covered[a:b] = True
    assert (covered | ~mask).all()


@settings(max_examples=40, deadline=None)  # a pure function; the cores are shared
@given(st.lists(st.integers(1, 30), min_size=1, max_size=4), st.data())
def test_split_segments_tiles_each_segment_and_keeps_its_goal_last(
    lengths: list[int], data: st.DataObject
) -> None:
    starts = np.concatenate([[0], np.cumsum(lengths)]).tolist()
    segs = tuple(GoalSegment(i, starts[i], starts[i + 1], f"g{i}") for i in range(len(lengths)))
    decisions = []
    for seg in segs:
        if seg.stop - seg.start >= 3 and data.draw(st.booleans()):
            d = data.draw(st.integers(seg.start + 1, seg.stop - 2))
            e = data.draw(st.integers(d + 1, seg.stop - 1))
            decisions.append(DecisionPoint(seg.index, "left", d, e, 1, seg.start, 0.0, 1.0, 0.5))
    out = split_segments(segs, decisions)
    assert [sub.index for _, sub in out] == list(range(len(out)))
    for seg in segs:
        subs = [sub for orig, sub in out if orig == seg.index]
        assert subs[0].start == seg.start and subs[-1].stop == seg.stop
        assert all(a.stop == b.start for a, b in zip(subs, subs[1:], strict=False))
        assert [s.goal for s in subs] == [None] * (len(subs) - 1) + [seg.goal]
        assert len(subs) == 1 + 2 * sum(d.segment == seg.index for d in decisions)


def _track(
    turn: np.ndarray, onset_at: int, side: int = 0, ahead_m: np.ndarray | None = None, other_m: float = 8.0
) -> LandmarkTrack:
    """A track of ``turn`` per step, one opening onset on ``side`` at ``onset_at``, the beam
    straight ahead reaching ``ahead_m`` (8 m where not given) and the beam abeam on the other
    side ``other_m``; the sectors held at the heading from before the turn."""
    onsets = np.zeros((N, 2), dtype=bool)
    onsets[onset_at, side] = True
    heading = np.cumsum(turn)
    first = int(np.argmax(turn != 0)) if (turn != 0).any() else N
    held = np.where(np.arange(N) >= first, heading - (heading[first - 1] if first else 0.0), 0.0)
    ranges = np.full((N, 3), 8.0)
    ranges[:, 0 if side == 0 else 2] = other_m  # beams at -90°, 0°, +90°
    if ahead_m is not None:
        ranges[:, 1] = ahead_m
    return LandmarkTrack(onsets, np.full(N, 0.04), turn, held, ranges, GEOM, OpeningParams())


def _demo(diverging: list[int], sgn: float = 1.0, deg: float = 60.0) -> np.ndarray:
    heading = np.zeros(N)
    heading[diverging] = sgn * math.radians(deg)
    return np.stack([np.cos(heading), np.sin(heading)], axis=1)


def _find(
    demo: np.ndarray, track: LandmarkTrack, params: DecisionParams = DecisionParams()
) -> list[DecisionPoint]:
    fused = np.tile([1.0, 0.0], (N, 1))
    return find_decisions(
        segments=SEGS, demo=demo, informative=np.ones(N, bool), fused=fused, track=track, params=params
    )


def test_a_divergence_broken_up_while_the_teacher_turns_is_one_decision() -> None:
    """Two bursts 10 steps apart, each too small to be a decision alone (at a spur the
    fused heading swings with the BACs as the teacher turns in): one, when runs 20 steps apart
    are joined."""
    turn = np.zeros(N)
    turn[40:60] = math.radians(90.0) / 20
    track = _track(turn, 38)
    demo = _demo([40, 50], deg=80.0)  # smoothed: 5 steps of 16° each, Σ 1.4 rad·steps
    (d,) = _find(demo, track, DecisionParams(min_area=2.0, max_gap=20))
    assert d.side == "left" and 38 <= d.onset < d.turn_end
    # the default gap: two runs (the teacher's own turn, a junction, left out: it is the next law)
    assert _find(demo, track, DecisionParams(min_area=2.0, junctions=False)) == []


def test_a_turn_begun_well_after_the_divergence_is_still_found() -> None:
    """The teacher leaves the fused heading at steps 40-45 and turns into the opening 30 steps
    later (a spur a few metres past a corner): found when the turn is looked for 40 steps on."""
    turn = np.zeros(N)
    turn[75:90] = math.radians(90.0) / 15
    track = _track(turn, 72)
    demo = _demo(list(range(40, 46)))
    (d,) = _find(demo, track, DecisionParams(rise_steps=40))
    assert d.onset == 72 and d.turn_end > 75
    assert _find(demo, track, DecisionParams(junctions=False)) == []  # the default: looked for too early


def test_the_shape_is_the_way_ahead_before_a_teacher_cut_in() -> None:
    """A teacher who cut into a side opening saw the far wall at its onset; the way ahead was open
    a moment before, as a robot driving on sees it. A corner is closed all along."""
    turn = np.zeros(N)
    turn[40:60] = math.radians(90.0) / 20
    cut = np.where(np.arange(N) >= 30, 2.0, 8.0)  # the view ahead closes 8 steps before the onset
    demo = _demo(list(range(40, 50)))
    before = DecisionParams(shape_steps=25)
    (d,) = _find(demo, _track(turn, 38, ahead_m=cut), replace(before, skip_corners=False))
    assert d.ahead_open is True
    (d,) = _find(demo, _track(turn, 38, ahead_m=cut), DecisionParams(skip_corners=False))
    assert d.ahead_open is False  # the default: read at the onset
    corner = np.full(N, 2.0)
    (d,) = _find(demo, _track(turn, 38, ahead_m=corner, other_m=1.0), replace(before, skip_corners=False))
    assert d.ahead_open is False
    assert _find(demo, _track(turn, 38, ahead_m=corner, other_m=1.0), before) == []  # a corner: no other way
    assert len(_find(demo, _track(turn, 38, ahead_m=cut, other_m=1.0), before)) == 1  # the cut-in: no corner
    assert _find(demo, _track(turn, 38, ahead_m=cut, other_m=1.0)) == []  # read at the onset, it looks one


def test_an_opening_counts_at_least_first_where_the_one_before_was_turned_into() -> None:
    """An onset flickering 0.8 m after an opening the teacher turned into is that opening: nothing
    was passed, and the landmark is the 1st (``nth`` 0 was written to tables that ``execute``
    then refused: seeds 1043 and 1044 of the generated worlds)."""
    turn = np.zeros(N)
    turn[8:18] = math.radians(60.0) / 10
    onsets = np.zeros((N, 2), dtype=bool)
    onsets[[5, 25], 0] = True
    track = LandmarkTrack(
        onsets, np.full(N, 0.04), turn, np.zeros(N), np.full((N, 3), 8.0), GEOM, OpeningParams()
    )
    assert opening_order(track, 0, 0, 25, OpeningCue.PASSED, DecisionParams().passing) == 1


@settings(max_examples=30, deadline=None)  # a pure function; the cores are shared
@given(st.integers(0, 3), st.floats(0.2, 1.4), st.booleans())
def test_a_flickering_onset_has_the_order_of_its_opening(passed: int, flicker_m: float, turn: bool) -> None:
    """An onset ``flicker_m`` after the first onset of an opening is that opening: counted at its
    first onset it has the order of the openings passed before it plus one, whether the robot
    then turned into it or drove past (``first_onset``). Without it, an opening turned into was
    one short (seed 1935 of the corrections bench: the 1st passed opening, a spur before it)."""
    n, step = 300, 0.1
    first = 10 + 40 * passed  # the openings before it 4 m apart: each passed by
    onsets = np.zeros((n, 2), dtype=bool)
    onsets[[10 + 40 * k for k in range(passed)], 0] = True
    d = first + round(flicker_m / step)
    onsets[[first, d], 0] = True
    rates = np.zeros(n)
    if turn:
        rates[first + 1 : first + 11] = math.radians(60.0) / 10
    track = LandmarkTrack(
        onsets, np.full(n, step), rates, np.zeros(n), np.full((n, 3), 8.0), GEOM, OpeningParams()
    )
    passing = DecisionParams().passing
    assert opening_order(track, 0, 0, d, OpeningCue.PASSED, passing, first_onset=True) == passed + 1
    old = opening_order(track, 0, 0, d, OpeningCue.PASSED, passing)
    if not turn:
        assert old == passed + 1
    elif d >= first + 12:  # the turn into it was counted (past 45°) before the flicker
        assert old == max(passed, 1)


@settings(max_examples=30, deadline=None)  # a pure function; the cores are shared
@given(
    st.sampled_from([0, 1]),
    st.integers(30, 70),
    st.floats(50.0, 120.0),
    st.integers(8, 25),
)
def test_a_turn_off_the_learned_fusion_follows_is_a_decision_only_with_junctions(
    side: int, start: int, deg: float, steps: int
) -> None:
    """Replayed on the teacher's own track, the learned fusion turns where the teacher turns (it
    sees the opening the teacher already turns into): no divergence, no decision without
    ``junctions``. With them (the default) the teacher's own turn off a way that goes on is one, at the opening's onset
    on the turn's side; off a way that ends (a corner, a T) it is not."""
    sgn = 1.0 if side == 0 else -1.0
    turn = np.zeros(N)
    turn[start : start + steps] = sgn * math.radians(deg) / steps
    onset = start - 2
    track = _track(turn, onset, side)
    heading = np.cumsum(turn)
    demo = np.stack([np.cos(heading), np.sin(heading)], axis=1)

    def find(track: LandmarkTrack, params: DecisionParams, informative: bool = True) -> list[DecisionPoint]:
        ok = np.full(N, informative)
        return find_decisions(
            segments=SEGS, demo=demo, informative=ok, fused=demo, track=track, params=params
        )

    assert find(track, DecisionParams(junctions=False)) == []
    (d,) = find(track, DecisionParams())
    assert d.side == ("left" if side == 0 else "right") and d.onset == onset and d.nth == 1
    assert onset < d.turn_end <= start + steps + 1
    assert d.divergence_rad == 0.0 and d.ahead_open is True
    ends = _track(turn, onset, side, ahead_m=np.full(N, 2.0))  # the way ahead closed: a corner or a T
    assert find(ends, DecisionParams()) == []
    assert find(track, DecisionParams(), informative=False) == []  # the network's turn (a correction log)


@settings(max_examples=30, deadline=None)  # a pure function; the cores are shared
@given(
    st.sampled_from([0, 1]),
    st.integers(30, 70),
    st.floats(50.0, 120.0),
    st.integers(8, 25),
    st.data(),
)
def test_a_forced_turn_is_a_decision_whatever_the_way_ahead_and_a_cue_can_be_chosen(
    side: int, start: int, deg: float, steps: int, data: st.DataObject
) -> None:
    """``forced`` (a rollout left the teacher's path in this turn): the teacher's turn is a
    decision even off a way that ends (a T, where junctions make none), its shape not named;
    a step outside every turn forces nothing. ``cues`` picks the landmark cue of the decision at
    an onset, the rest of it unchanged."""
    sgn = 1.0 if side == 0 else -1.0
    turn = np.zeros(N)
    turn[start : start + steps] = sgn * math.radians(deg) / steps
    onset = start - 2
    ends = _track(turn, onset, side, ahead_m=np.full(N, 2.0), other_m=8.0)
    heading = np.cumsum(turn)
    demo = np.stack([np.cos(heading), np.sin(heading)], axis=1)
    ok = np.ones(N, bool)

    def find(**kw: object) -> list[DecisionPoint]:
        return find_decisions(segments=SEGS, demo=demo, informative=ok, fused=demo, track=ends, **kw)  # type: ignore[arg-type]

    assert find() == []
    k = data.draw(st.integers(start + steps // 2, start + steps - 1))  # in the turn, past its first 8°
    (d,) = find(forced=[k])
    assert d.side == ("left" if side == 0 else "right") and d.onset == onset and d.ahead_open is None
    assert onset < d.turn_end < N
    assert find(forced=[data.draw(st.integers(0, start - 12))]) == []
    (e,) = find(forced=[k], cues={onset: OpeningCue.DISTANCE})
    assert e.cue == OpeningCue.DISTANCE and e.within_m is not None
    assert (e.onset, e.turn_end, e.angle_rad, e.side) == (d.onset, d.turn_end, d.angle_rad, d.side)
    assert find(forced=[k], cues={onset + 1: OpeningCue.DISTANCE}) == [d]  # another onset: no change
    # ``whole``: the decision at that onset turns the teacher's whole turn (from the held heading)
    (w,) = find(forced=[k], whole=[onset])
    assert w.angle_rad >= d.angle_rad and w.turn_end >= d.turn_end
    assert w.angle_rad == pytest.approx(min(math.radians(deg), math.radians(150)), abs=1e-6)
    assert find(forced=[k], whole=[onset + 1]) == [d]


def test_a_forced_turn_the_goal_cuts_short_ends_before_the_goal() -> None:
    """The teacher still turning when the goal was reached (a spur just round a corner): forced,
    the turn step ends ``min_steps`` before the goal with the angle turned by then."""
    turn = np.zeros(N)
    turn[80:] = np.diff(math.radians(90.0) * (np.arange(41) / 40) ** 2)  # faster and faster, to the goal
    track = _track(turn, 78, 0, ahead_m=np.full(N, 2.0))
    heading = np.cumsum(turn)
    demo = np.stack([np.cos(heading), np.sin(heading)], axis=1)
    p = DecisionParams()
    (d,) = find_decisions(
        segments=SEGS, demo=demo, informative=np.ones(N, bool), fused=demo, track=track, forced=[110]
    )
    assert d.turn_end == N - p.min_steps
    assert d.angle_rad == pytest.approx(track.held_rad[d.turn_end])  # as far as the teacher had turned
    assert (
        find_decisions(segments=SEGS, demo=demo, informative=np.ones(N, bool), fused=demo, track=track) == []
    )  # not forced: the goal came first


@settings(max_examples=30, deadline=None)
@given(st.floats(10.0, 30.0), st.floats(45.0, 75.0))
def test_a_forced_turn_whose_goal_lies_beyond_its_window_is_read_within_it(right: float, left: float) -> None:
    """A forced turn that turned less than a decision's least turn from the heading the sectors
    held (a little right first, the sectors held on, then left), its goal far beyond the turn's
    window: read within the window, where it is no decision (read at the goal, past the
    window's headings, it was an index error)."""
    assume(left - right < math.degrees(DecisionParams().min_angle_rad) - 1.0)
    turn = np.zeros(N)
    turn[20:30] = -math.radians(right) / 10
    turn[40:50] = math.radians(left) / 10
    heading = np.cumsum(turn)
    held = np.where((np.arange(N) >= 20) & (np.arange(N) < 56), heading, 0.0)  # held again after
    onsets = np.zeros((N, 2), dtype=bool)
    onsets[38, 0] = True
    ranges = np.full((N, 3), 8.0)
    ranges[:, 1] = 2.0
    track = LandmarkTrack(onsets, np.full(N, 0.04), turn, held, ranges, GEOM, OpeningParams())
    demo = np.stack([np.cos(heading), np.sin(heading)], axis=1)
    ok = np.ones(N, bool)
    assert (
        find_decisions(segments=SEGS, demo=demo, informative=ok, fused=demo, track=track, forced=[45]) == []
    )


@settings(max_examples=30, deadline=None)
@given(st.sampled_from([0, 1]), st.integers(30, 60), st.floats(50.0, 80.0), st.integers(10, 24))
def test_a_corner_taken_in_two_is_a_decision_only_when_forced(
    side: int, start: int, deg: float, steps: int
) -> None:
    """The sectors held again halfway through the teacher's turn (a corner taken in two): the
    turn never leaves the held heading by ``min_turn_rad`` though the heading rose that far. A
    rollout left the path there (``forced``): it is a decision; not forced, none; a turn that
    left the held heading by less than ``blamed_turn_rad`` is none even forced."""
    p = DecisionParams()
    sgn = 1.0 if side == 0 else -1.0
    turn = np.zeros(N)
    turn[start : start + steps] = sgn * math.radians(deg) / steps
    track = _track(turn, start - 2, side, ahead_m=np.full(N, 2.0))
    half = start + steps // 2
    heading = np.cumsum(turn)
    held = np.where(np.arange(N) >= half, heading - heading[half - 1], track.held_rad)
    two = replace(track, held_rad=held)
    assert float(np.abs(held).max()) < p.min_turn_rad
    demo = np.stack([np.cos(heading), np.sin(heading)], axis=1)
    ok = np.ones(N, bool)

    def find(t: LandmarkTrack, forced: list[int]) -> list[DecisionPoint]:
        return find_decisions(segments=SEGS, demo=demo, informative=ok, fused=demo, track=t, forced=forced)

    assume(float(np.abs(held[start:half]).max()) >= p.blamed_turn_rad)
    (d,) = find(two, [half - 1])  # in the first half, past its first 8°
    assert d.side == ("left" if side == 0 else "right") and d.onset == start - 2
    assert find(two, []) == []
    small = replace(two, held_rad=held * (0.9 * p.blamed_turn_rad / float(np.abs(held).max())))
    assert find(small, [half - 1]) == []


def test_a_turn_the_default_sectors_sensed_no_opening_at_is_decided_by_the_shorter_lag() -> None:
    """Where the default sectors sensed no onset near the teacher's turn (swinging through the turn
    of a corner just before), the opening the sensor with the shorter lag met decides, and the
    decision names that lag; where the default sectors sensed it, they decide alone."""
    demo, fused, seen = _turn_off()
    _, _, blind = _turn_off(onset_at=None)
    short = replace(seen, params=replace(seen.params, lag_m=1.5))
    ok = np.ones(N, bool)

    def found(track: LandmarkTrack, params: DecisionParams = DecisionParams()) -> list[DecisionPoint]:
        return find_decisions(
            segments=SEGS, demo=demo, informative=ok, fused=fused, track=track, params=params
        )

    (by_default,) = found(seen)
    (by_short,) = found(replace(blind, short=short))
    assert by_default.lag_m is None and by_short.lag_m == 1.5
    assert replace(by_short, lag_m=None) == by_default  # the same opening, turn and landmarks
    assert found(replace(seen, short=short)) == [by_default]
    assert found(replace(blind, short=short), DecisionParams(short_lag_m=None)) == []
    assert found(blind) == []
