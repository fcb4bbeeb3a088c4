"""A goal step's rows with its goal in view, learned from the teacher's approach alone: which steps
are dropped and pooled, the rows written, and a goal driven past that the repair then reaches."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse import learn
from lfdfuse.estimate.approach import HOMING_RAD, Approach, approach_run, homing_begins, spread
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.subgoals import refine, track_of
from lfdfuse.execute.check import demo_world, drive
from lfdfuse.execute.repair import Amends
from lfdfuse.log.reader import read_run
from lfdfuse.network.table import FusionRow, Step
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.read import SegmentedRun, read_segmented
from tests.support.generated import THREE_GOALS
from tests.support.generated_worlds import generate_offroute

NAMES = ("avoid", "attract_red", "wander", "wall_attract_left")
N = 200


def _unit(rad: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(rad), np.sin(rad)], axis=1)


def _run(in_view: int, homing: int, walls: np.ndarray, away_deg: float) -> SegmentedRun:
    """One goal segment of ``N`` steps: red in view from ``in_view`` (dead ahead), the teacher
    heading ``away_deg`` off it until ``homing``, straight at it after; the left wall applicable
    where ``walls``; avoid and wander always."""
    k = np.arange(N)
    seen = k >= in_view
    app = np.stack([np.ones(N, bool), seen, np.ones(N, bool), walls], axis=1)
    goal = _unit(np.zeros(N)) * seen[:, None]
    demo = _unit(np.where(k < homing, math.radians(away_deg), 0.0))
    vectors = np.stack([_unit(np.full(N, 2.0)), goal, _unit(np.full(N, 0.5)), _unit(np.full(N, 1.5))], axis=1)
    bac = (app * (1 << np.arange(len(NAMES)))).sum(axis=1).astype(np.int64)
    return SegmentedRun(
        NAMES,
        k.astype(np.int64),
        vectors,
        app,
        np.zeros((N, len(NAMES)), bool),
        demo,
        np.ones(N, bool),
        bac,
        np.zeros(N, np.int64),
        (GoalSegment(0, 0, N, "attract_red"),),
        {},
    )


@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 150),
    st.integers(0, 190),
    st.lists(st.booleans(), min_size=N, max_size=N),
    st.floats(math.degrees(HOMING_RAD) + 1.0, 90.0),
)
def test_the_goal_in_view_before_the_approach_teaches_nothing_and_the_approach_is_one_bac(
    in_view: int, homing: int, walls: list[bool], away_deg: float
) -> None:
    w = np.asarray(walls)
    run = _run(in_view, homing, w, away_deg)
    begins = homing_begins(run, run.segments[0])
    assert begins == (homing if homing > in_view else 0)  # after the last step it looked away
    moved, found = approach_run(run, run.segments)
    seen = np.arange(N) >= in_view
    (a,) = found
    before = seen & (np.arange(N) < begins)
    assert np.array_equal(moved.informative, ~before)
    assert np.all(moved.bac[~seen] == run.bac[~seen])  # the goal out of view: untouched
    assert np.all(moved.bac[seen] == a.pooled)
    assert a.pooled == int(np.bitwise_or.reduce(run.bac[begins:]))
    assert set(a.in_view) == set(run.bac[seen].tolist())
    # a behaviour not applicable at a step adds nothing there, in the pooled BAC too
    off = seen[:, None] & ~run.applicable
    assert np.all(moved.vectors[off] == 0.0)
    assert np.array_equal(moved.vectors[~off], run.vectors[~off])


def test_a_goal_never_in_view_leaves_the_run_as_it_is() -> None:
    run = _run(N, 0, np.ones(N, bool), 40.0)
    assert homing_begins(run, run.segments[0]) is None
    moved, found = approach_run(run, run.segments)
    assert found == () and moved is not run and np.array_equal(moved.bac, run.bac)


def test_the_pooled_row_is_written_for_every_bac_with_the_goal_in_view() -> None:
    pooled = FusionRow(
        0b1111, {"avoid": 0.1, "attract_red": 0.7, "wander": 0.05, "wall_attract_left": 0.15}, samples=40
    )
    other = FusionRow(0b0101, {"avoid": 0.3, "wander": 0.7}, samples=90)
    step = Step("reach-red", "red", (other, pooled))
    out = spread(step, Approach(0, 0b1111, (0b0111, 0b1111)), NAMES)
    assert [r.bac for r in out.fusion] == [0b0101, 0b0111, 0b1111]
    assert out.row(0b0101) == other
    assert out.row(0b0111) is not None and out.row(0b0111).weights == {
        "avoid": 0.1,
        "attract_red": 0.7,
        "wander": 0.05,
    }  # type: ignore[union-attr]
    assert out.row(0b1111).weights == pooled.weights and out.row(0b1111).samples == 40  # type: ignore[union-attr]


def test_a_goal_driven_past_is_reached_with_the_approach_rows(tmp_path: Path) -> None:
    """Generated world 150 (a tuning world): from the teacher's own start the learned table
    drives along the corridor past blue (its row with blue in view and only the right wall was
    learned where the teacher drove on, blue far ahead). The check finds the goal missed with the
    path followed and repairs blue's step with the approach rows; the table then reaches all three
    goals, and every other step is as learned."""
    world = generate_offroute(150)
    demo = learn.demonstrate(THREE_GOALS, world=world, folder=tmp_path, name="d", duration_s=900.0, seed=1)
    run, raw = read_segmented(demo.segmented), read_run(demo.segmented)
    opts = learn.LearnOptions(EstimateOptions(), subgoals=True, check_starts=0)
    plain = learn.learn_run(run, options=learn.LearnOptions(EstimateOptions()), name="d").table
    track = track_of(raw, run)
    home = demo_world(raw, goals=3)
    assert home is not None
    blue = next(s.index for s in run.segments if s.goal == "attract_blue")
    rep = learn.subgoals_checked(plain, run, track, home, opts)
    (before,), (after,) = rep.checks[0], rep.kept
    assert before.goals == 2 and before.missed_at is None  # the path followed, blue driven past
    assert rep.amends == Amends(approach=(blue,)) and after.goals == 3
    assert drive(rep.table, world, home.start, home.max_time_s).goals == 3
    learned = refine(plain, run, track, opts=EstimateOptions()).table
    changed = [
        i
        for i, (a, b) in enumerate(zip(learned.network.steps, rep.table.network.steps, strict=True))
        if a != b
    ]
    assert changed == [blue]
    assert any("heads at its goal" in line for line in rep.describe())
