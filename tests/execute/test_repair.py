"""The repair of a table that leaves the teacher's path in the demo's world: what is blamed, what is
tried, and what is kept."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse import learn
from lfdfuse.behaviors.openings import OpeningParams
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.subgoals import refine, track_of
from lfdfuse.execute.check import Check, demo_world, drive, score
from lfdfuse.execute.repair import (
    BLAME_STEPS,
    Amends,
    _approach_of,
    _decided_at,
    _rest_of,
    _turned_at,
    blame,
    repair,
)
from lfdfuse.log.reader import read_run
from lfdfuse.network.table import FusionTable
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.segment.decisions import DecisionParams, DecisionPoint
from lfdfuse.segment.read import read_segmented
from lfdfuse.segment.track import LandmarkTrack, OpeningCue
from tests.support.generated import THREE_GOALS
from tests.support.generated_worlds import generate_offroute

GEOM = ScanGeometry(-math.pi / 2, math.pi / 2, 3, 8.0)


def test_a_table_that_leaves_the_teacher_in_the_demo_world_is_repaired(tmp_path: Path) -> None:
    """Generated world 117 (a tuning world): the sub-goal table learned by replay with the default
    opening sensor alone drives past the spur green is in, from the teacher's own start; the check
    makes the teacher's turn into it a decision, and the repaired table completes the task from
    that start. (With the shorter-lag sensor the turn is a decision at once, and nothing needs
    repair: ``DecisionParams.short_lag_m``.)"""
    world = generate_offroute(117)
    demo = learn.demonstrate(THREE_GOALS, world=world, folder=tmp_path, name="d", duration_s=900.0, seed=1)
    alone = DecisionParams(short_lag_m=None)
    res = learn.learn(
        [demo.segmented], options=learn.LearnOptions(subgoals=True, check_starts=0, decisions=alone)
    )
    rep = res.repair
    assert rep is not None and rep.changed and rep.amends.forced
    (before,), (after,) = rep.checks[0], rep.kept
    assert before.goals < 3 and before.missed_at is not None
    assert after.goals == 3 and score(rep.kept) > score(rep.checks[0])
    home = demo_world(read_run(demo.segmented), goals=3)
    assert home is not None and home.start.as_tuple() == pytest.approx(world.start)
    goals = drive(res.table, world, home.start, home.max_time_s).goals
    assert goals == 3  # the table written is the one checked
    assert res.decisions == rep.decisions and len(rep.describe()) >= 3


def test_a_goal_step_whose_sub_goals_mislead_is_learned_without_them(tmp_path: Path) -> None:
    """Generated world 175 (a tuning world): blue's step has a decision, and the sub-goal table
    leaves the teacher's path there from the teacher's own start (2 goals); the paper's step for
    blue reaches it. With no other repair to try (``candidates=0``), the check tries that goal
    step without its sub-goals, keeps it, and only that step changes."""
    world = generate_offroute(175)
    demo = learn.demonstrate(THREE_GOALS, world=world, folder=tmp_path, name="d", duration_s=900.0, seed=1)
    run, raw = read_segmented(demo.segmented), read_run(demo.segmented)
    home = demo_world(raw, goals=3)
    assert home is not None
    paper = learn.learn_run(run, options=learn.LearnOptions(EstimateOptions()), name="d").table
    track = track_of(raw, run)

    def refined(a: Amends) -> tuple[FusionTable, list[DecisionPoint]]:
        res = refine(paper, run, track, opts=EstimateOptions(), plain=a.plain)
        return res.table, list(res.decisions)

    segments = tuple((s.start, s.stop) for s in run.segments)
    rep = repair(refined, track=track, home=home, starts=(home.start,), segments=segments, candidates=0)
    (before,), (after,) = rep.checks[0], rep.kept
    learned, decisions = refined(Amends())
    blue = next(s.index for s in run.segments if s.goal == "attract_blue")
    assert before.goals == 2 and any(d.segment == blue for d in decisions)
    assert rep.amends == Amends(plain=(blue,)) and after.goals == 3 and len(rep.checks) == 2
    assert all(d.segment != blue for d in rep.decisions)
    changed = [
        i
        for i, (a, b) in enumerate(zip(learned.network.steps, rep.table.network.steps, strict=True))
        if a != b
    ]
    assert changed == [blue] and rep.table.network.steps[blue] == paper.network.steps[blue]
    assert any("no sub-goals" in line for line in rep.describe())


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.integers(20, 200), min_size=1, max_size=4),
    st.lists(st.tuples(st.integers(0, 3), st.integers(0, 150), st.integers(5, 60)), max_size=6),
    st.integers(0, 800),
    st.integers(0, 120),
)
def test_whole_turn_and_rest_blame_the_decision_made_and_the_segment_left(
    lengths: list[int], raw: list[tuple[int, int, int]], missed: int, back: int
) -> None:
    """Where the robot left the path after a turn: ``_turned_at`` names the last decision begun
    by the last point met and ended before the first one missed; ``_rest_of`` the goal segment
    the robot left it in, only when that was after the segment's last decision."""
    bounds = np.concatenate([[0], np.cumsum(lengths)]).tolist()
    segments = list(zip(bounds[:-1], bounds[1:], strict=True))
    decisions = []  # in time order, each turn ended before the next decision (as found)
    cursor = [lo for lo, _ in segments]
    for k, gap, dur in raw:
        if k >= len(segments) or cursor[k] + gap % 20 + dur >= segments[k][1]:
            continue
        onset = cursor[k] + gap % 20
        decisions.append(DecisionPoint(k, "left", onset, onset + dur, 1, cursor[k], 1.0, 1.0, 0.5))
        cursor[k] = onset + dur
    decisions.sort(key=lambda d: d.onset)
    last = max(missed - back, 0)
    c = Check(goals=0, met=1, points=9, missed_at=missed, last_met_at=last)

    def made(d: DecisionPoint) -> bool:
        return d.onset <= last + BLAME_STEPS and d.turn_end <= missed

    turned = _turned_at(decisions, c)
    if turned:
        (d,) = turned
        assert made(d) and not any(made(e) for e in decisions[decisions.index(d) + 1 :])
    else:
        assert not any(made(e) for e in decisions)
    rest = _rest_of(decisions, segments, c)
    inside = [k for k, (lo, hi) in enumerate(segments) if lo <= missed < hi]
    if rest:
        (k,) = rest
        assert inside == [k]
        assert all(d.turn_end <= missed for d in decisions if d.segment == k)
        assert any(d.segment == k for d in decisions)
    elif inside:
        mine = [d for d in decisions if d.segment == inside[0]]
        assert not mine or mine[-1].turn_end > missed
    followed = Check(goals=3, met=9, points=9, missed_at=None, last_met_at=last)
    assert _turned_at(decisions, followed) == [] and _rest_of(decisions, segments, followed) == []


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.integers(20, 200), min_size=1, max_size=4),
    st.one_of(st.none(), st.integers(0, 900)),
    st.sets(st.integers(0, 3)),
)
def test_a_goal_step_left_where_it_has_decisions_may_drop_them(
    lengths: list[int], missed: int | None, decided: set[int]
) -> None:
    """``_decided_at``: the goal segment the robot left the path in, exactly when it has a
    decision (the repair then tries it without its sub-goals); nothing when the path was followed
    or left outside every segment."""
    bounds = np.concatenate([[0], np.cumsum(lengths)]).tolist()
    segments = list(zip(bounds[:-1], bounds[1:], strict=True))
    decisions = [
        DecisionPoint(k, "left", lo + 3, lo + 8, 1, lo, 1.0, 1.0, 0.5)
        for k, (lo, _) in enumerate(segments)
        if k in decided
    ]
    c = Check(goals=0, met=1, points=9, missed_at=missed, last_met_at=0)
    got = _decided_at(decisions, segments, c)
    inside = [k for k, (lo, hi) in enumerate(segments) if missed is not None and lo <= missed < hi]
    assert got == [k for k in inside if k in decided]


def test_amends_say_what_they_change_and_a_cue_replaces_the_one_before() -> None:
    assert not Amends() and Amends(rest=(1,)) and Amends(whole=(5,)) and Amends(plain=(0,))
    a = Amends().with_cue(7, OpeningCue.ALL).with_cue(9, OpeningCue.PASSED).with_cue(7, OpeningCue.DISTANCE)
    assert dict(a.cues) == {7: OpeningCue.DISTANCE, 9: OpeningCue.PASSED}


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.integers(20, 200), min_size=1, max_size=4),
    st.integers(0, 4),
    st.one_of(st.none(), st.integers(0, 800)),
    st.sets(st.integers(0, 3)),
)
def test_the_approach_is_blamed_for_a_goal_missed_where_the_teacher_reached_it(
    lengths: list[int], goals: int, missed: int | None, decided: set[int]
) -> None:
    """``_approach_of``: the first goal not reached, when the robot followed the teacher's path to
    where the teacher reached it (``BLAME_STEPS`` before its segment's end, or to the end); never
    a goal step with a decision (its rows after the turn have their own repairs)."""
    bounds = np.concatenate([[0], np.cumsum(lengths)]).tolist()
    segments = list(zip(bounds[:-1], bounds[1:], strict=True))
    goal_segments = list(range(len(segments)))
    decisions = [
        DecisionPoint(k, "left", lo, lo + 5, 1, lo, 1.0, 1.0, 0.5)
        for k, (lo, _) in enumerate(segments)
        if k in decided
    ]
    c = Check(goals=goals, met=1, points=9, missed_at=missed, last_met_at=0)
    got = _approach_of(decisions, segments, goal_segments, c)
    if goals >= len(segments) or goals in decided:
        assert got == []
    elif missed is None or missed >= segments[goals][1] - BLAME_STEPS:
        assert got == [goals]
    else:
        assert got == []


@settings(max_examples=60, deadline=None)
@given(
    st.integers(10, 60), st.floats(21.0, 44.0), st.floats(46.0, 90.0), st.integers(0, 400), st.integers(0, 80)
)
def test_blame_takes_a_corner_taken_in_two_only_when_no_whole_turn_is_near(
    start: int, small_deg: float, big_deg: float, missed: int, back: int
) -> None:
    """``blame``: the last turn that left the held heading by ``min_turn_rad`` near where the
    robot left the path; failing one, the last that left it by ``blamed_turn_rad``."""
    p = DecisionParams()
    n = 500
    held = np.zeros(n)
    small = (start, start + 30)
    big = (start + 200, start + 230)
    held[small[0] : small[1]] = math.radians(small_deg) * np.sin(np.linspace(0.1, math.pi - 0.1, 30))
    held[big[0] : big[1]] = -math.radians(big_deg) * np.sin(np.linspace(0.1, math.pi - 0.1, 30))
    track = LandmarkTrack(
        np.zeros((n, 2), bool), np.full(n, 0.04), np.zeros(n), held, np.zeros((n, 3)), GEOM, OpeningParams()
    )
    c = Check(goals=0, met=1, points=9, missed_at=missed, last_met_at=max(missed - back, 0))

    def near(a: int, b: int) -> bool:
        on = np.nonzero(np.abs(held[a:b]) > p.began_rad)[0]
        a2, b2 = a + int(on[0]), a + int(on[-1]) + 1
        return a2 <= missed and b2 >= c.last_met_at - BLAME_STEPS

    got = blame(track, c, p)
    if near(*big):
        assert got is not None and big[0] <= got < big[1]
    elif near(*small):
        assert got is not None and small[0] <= got < small[1]
    else:
        assert got is None


def test_a_table_refined_again_from_other_amends_is_not_driven_again(monkeypatch: pytest.MonkeyPatch) -> None:
    """Two amends may refine to the same table; the check drives each table once (a rollout is
    deterministic), and the table refined again is still one of the tables tried."""
    import lfdfuse.execute.repair as repair_module
    from lfdfuse.execute.check import DemoWorld
    from lfdfuse.network.table import FusionRow, Network, Step
    from lfdfuse.robot.pose import Pose
    from lfdfuse.world.model import load_world

    def table(weight: float) -> FusionTable:  # a new object each call: equal, never the same one
        row = FusionRow(bac=1, weights={"avoid": weight, "attract_red": 1.0 - weight})
        step = Step(name="red", goal="red", fusion=(row,))
        return FusionTable(
            ("avoid", "attract_red"), {"avoid": 0.5, "attract_red": 0.5}, Network("task", (step,))
        )

    driven: list[FusionTable] = []

    def check_all(t: FusionTable, *_: object) -> tuple[Check, ...]:
        driven.append(t)
        return (Check(goals=0, met=5, points=10, missed_at=None, last_met_at=50),)

    monkeypatch.setattr(repair_module, "check_all", check_all)
    home = DemoWorld(load_world("corridor"), Pose(1.0, 1.0, 0.0), np.zeros((100, 2)), 10.0, goals=1)
    track = LandmarkTrack.__new__(LandmarkTrack)  # not read: no rollout leaves the path
    weights = {Amends(): 0.3, Amends(approach=(0,)): 0.3}
    rep = repair(
        lambda a: (table(weights.get(a, 0.7)), []),
        track=track,
        home=home,
        starts=(home.start,),
        segments=((0, 100),),
        goal_segments=(0,),
    )
    assert len(rep.checks) == 2 and rep.checks[0] == rep.checks[1]  # the approach was tried
    assert driven == [table(0.3)] and rep.amends == Amends() and not rep.changed
