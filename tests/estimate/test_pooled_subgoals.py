"""Decisions matched across demos, and a correction's change said per step (the pieces; the
whole on a building: tests/execute/test_correction_subgoals.py)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from lfdfuse.estimate.pooled_subgoals import Verdict, same_place
from lfdfuse.estimate.sub_step_corrections import (
    NETWORK_GOAL_TICKS,
    FurtherDemo,
    goals_of_network,
    goals_once,
    taken_over,
)
from lfdfuse.network.changes import step_changes
from lfdfuse.network.landmark_goals import Landmark
from lfdfuse.network.table import FusionRow, FusionTable, Network, Step
from lfdfuse.segment.decisions import DecisionPoint
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.read import SegmentedRun

SPUR = DecisionPoint(
    segment=1,
    side="left",
    onset=400,
    turn_end=440,
    nth=2,
    since=300,
    odometry_m=12.0,
    angle_rad=math.radians(85.0),
    divergence_rad=0.5,
    ahead_open=True,
)


def test_the_same_turn_off_is_matched_within_its_tolerance_and_nothing_else() -> None:
    assert same_place(SPUR, replace(SPUR, odometry_m=14.5, nth=3, onset=900, since=800))  # 30 % of 12 m
    assert not same_place(SPUR, replace(SPUR, odometry_m=16.0))
    assert same_place(replace(SPUR, odometry_m=2.0), replace(SPUR, odometry_m=3.4))  # at least 1.5 m
    assert not same_place(SPUR, replace(SPUR, side="right"))
    assert not same_place(SPUR, replace(SPUR, ahead_open=False))  # a corner is not a side opening
    assert same_place(SPUR, replace(SPUR, ahead_open=None))  # a shape one demo did not name
    assert not same_place(SPUR, replace(SPUR, angle_rad=math.radians(150.0)))
    assert not same_place(SPUR, replace(SPUR, at_start=True))


def test_a_verdict_says_what_where_and_why() -> None:
    line = Verdict("added", "reach-green", SPUR, ("fix.seg.mcap",), "the person turned off").describe()
    assert (
        line
        == "added    reach-green: turn 85° left at opening 2, 12.0 m (fix.seg.mcap): the person turned off"
    )


def _row(bac: int, w: float) -> FusionRow:
    return FusionRow(
        bac=bac, weights={"a": w, "b": 1.0 - w}, std={"a": 0.1, "b": 0.1}, samples=40, fit_error_deg=5.0
    )


def _table(*steps: Step) -> FusionTable:
    return FusionTable(("a", "b"), {"a": 0.5, "b": 0.5}, Network("t", steps))


def test_step_changes_name_new_sub_goals_and_re_weighted_rows_only() -> None:
    red = Step("reach-red", "red", (_row(3, 0.4),))
    green = Step("reach-green", "green", (_row(3, 0.5), _row(1, 0.9)))
    old = _table(red, green)
    assert step_changes(old, old) == []
    reweighted = _table(red, replace(green, fusion=(_row(3, 0.6), _row(1, 0.9), _row(2, 0.2))))
    assert step_changes(old, reweighted) == ["reach-green: re-weights 1 row(s), adds 1 row(s)"]
    inner = (
        replace(green, name="to-left-opening-2", goal=None, landmark=Landmark("opening", "left", 2, 12.0)),
        Step("turn-left", None, (_row(3, 0.1),), landmark=Landmark("turned", "left", angle_rad=1.4)),
        green,
    )
    nested = _table(red, Step("reach-green", "green", (), Network("reach-green", inner)))
    (line,) = step_changes(old, nested)
    assert line == (
        "reach-green: now to-left-opening-2 (the 2nd opening on the left (the teacher met it after 12.0 m))"
        " → turn-left (turned 80° to the left) → reach-green"
    )


def _run(*segs: tuple[int, str | None]) -> SegmentedRun:
    """A run of goal segments of these lengths and goals (nothing else in it matters here)."""
    n = sum(k for k, _ in segs)
    bounds = np.cumsum([0, *(k for k, _ in segs)])
    segments = tuple(
        GoalSegment(i, int(a), int(b), g)
        for i, (a, b, (_, g)) in enumerate(zip(bounds[:-1], bounds[1:], segs, strict=True))
    )
    seg_of = np.repeat(np.arange(len(segs)), [k for k, _ in segs])
    z = np.zeros(n)
    return SegmentedRun(
        ("avoid",),
        z.astype(np.int64),
        np.zeros((n, 1, 2)),
        np.ones((n, 1), bool),
        np.zeros((n, 1), bool),
        np.zeros((n, 2)),
        np.ones(n, bool),
        np.ones(n, np.int64),
        seg_of,
        segments,
        {},
    )


def test_a_goal_met_again_while_lingering_starts_no_goal_segment_of_a_correction() -> None:
    red, green, blue = "attract_red", "attract_green", "attract_blue"
    run = _run((10, red), (30, green), (5, green), (4, green), (20, blue))
    once = goals_once(run)
    assert [(s.start, s.stop, s.goal) for s in once.segments] == [
        (0, 10, red),
        (10, 40, green),
        (40, 69, blue),
    ]
    assert once.segment_of.tolist() == [0] * 10 + [1] * 30 + [2] * 29
    ended = goals_once(_run((10, red), (30, green), (5, green)))  # never on to blue: a tour after green
    assert [(s.start, s.stop, s.goal) for s in ended.segments] == [
        (0, 10, red),
        (10, 40, green),
        (40, 45, None),
    ]
    plain = _run((10, red), (30, green), (20, None))
    assert goals_once(plain) is plain


def test_every_takeover_of_a_person_who_watched_on_names_the_step_the_network_was_in() -> None:
    run = _run((10, "attract_red"), (30, "attract_green"), (20, "attract_blue"))
    steps = ("reach-red",) * 10 + ("reach-green/to-left-opening-1",) * 30 + ("reach-blue",) * 20
    rng = np.random.default_rng(0)
    for _ in range(50):  # two stretches the person drove, not every tick of them informative
        a, b, c, d = sorted(rng.choice(np.arange(61), 4, replace=False).tolist())
        person = np.zeros(60, bool)
        person[a:b] = person[c:d] = True
        fix = replace(run, informative=person & (rng.random(60) > 0.3))
        ticks = np.nonzero(fix.informative)[0]

        def taken(who: np.ndarray | None, fix: SegmentedRun = fix) -> set[str]:
            return taken_over([FurtherDemo("fix", fix, None, True, steps, who)])  # type: ignore[arg-type]

        def first_at(t: int, ticks: np.ndarray = ticks) -> set[str]:
            after = ticks[ticks >= t]
            return {steps[int(after[0])].split("/")[0]} if len(after) else set()

        # without /lfd/authority: the first informative tick's step; with it, each takeover's
        assert taken(None) == first_at(0)
        assert taken(person) == first_at(a) | first_at(c)
        # one takeover: as without /lfd/authority
        one = replace(fix, informative=fix.informative & (np.arange(60) < b))
        mask = person & (np.arange(60) < b)
        assert taken_over([FurtherDemo("f", one, None, True, steps, mask)]) == taken_over(  # type: ignore[arg-type]
            [FurtherDemo("f", one, None, True, steps)]  # type: ignore[arg-type]
        )


def _steps(*spans: tuple[int, str | None]) -> tuple[str | None, ...]:
    """The network's step per tick: ``spans`` of (ticks, step name)."""
    return tuple(name for k, name in spans for _ in range(k))


GOALS = {"reach-red": "attract_red", "reach-green": "attract_green", "reach-blue": "attract_blue"}


def test_a_target_met_while_the_network_was_after_another_goal_starts_no_goal_segment() -> None:
    red, green, blue = "attract_red", "attract_green", "attract_blue"
    # red met (the network on to green there), blue passed on the way to green, red come round to
    # again; green never reached: the tail is the way to green
    run = _run((10, red), (30, blue), (40, red), (20, None))
    steps = _steps((9, "reach-red"), (91, "reach-green/to-left-opening-2"))
    mine = goals_of_network(run, steps, GOALS)
    assert [(s.start, s.stop, s.goal) for s in mine.segments] == [(0, 10, red), (10, 100, None)]
    assert mine.segment_of.tolist() == [0] * 10 + [1] * 90
    # every target met as the network's goal: the run as it is, whatever the sub-steps
    plain = _run((10, red), (30, green), (20, blue))
    steps = _steps((9, "reach-red"), (30, "reach-green/turn-left"), (20, "reach-blue"), (1, None))
    assert goals_of_network(plain, steps, GOALS) is plain
    # lingering at green (met again, the network after blue) is dropped as goals_once drops it
    linger = _run((10, red), (30, green), (5, green), (20, blue))
    steps = _steps((9, "reach-red"), (30, "reach-green"), (25, "reach-blue"), (1, None))
    assert goals_of_network(linger, steps, GOALS).segments == goals_once(linger).segments


def test_the_network_met_its_goal_within_a_few_ticks_of_the_segmenter_or_not_at_all() -> None:
    red = "attract_red"
    run = _run((10, red), (10, None))
    for late in range(-NETWORK_GOAL_TICKS - 3, 3):
        # the network left reach-red ``late`` ticks after the segmenter saw red met (tick 9)
        steps = _steps((10 + late, "reach-red"), (10 - late, "reach-green"))
        kept = [s.goal for s in goals_of_network(run, steps, GOALS).segments]
        assert kept == ([red, None] if late >= -NETWORK_GOAL_TICKS else [None])
