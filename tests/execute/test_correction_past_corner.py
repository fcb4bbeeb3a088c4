"""A correction's turn into a branch just past a corner becomes a decision, and fixes the table.

Generated world 1952 (corrections range, below the seeds held apart for the final number): green
lies down a branch on the right 4 m past a left corner. Opening onsets are sensed with sectors
held at the heading from before a turn, so as the robot swings through the corner the branch
reads as the corner's wall: the demo has no decision there and the table, learned without one,
drives on past the branch from every start. A scripted person (:mod:`tests.support.corrections`)
takes over before the branch and turns into it. Their first turn after taking over is the turn
they took over for (:func:`lfdfuse.estimate.sub_step_corrections.taken_over_turns`): learned
with the demo (:mod:`lfdfuse.estimate.pooled_subgoals`) it becomes a decision of reach-green, and
the new table completes from the failed start; with that turn not forced, the same correction
adds no decision (the turn reads as a corner).

Learned as the ``corrections`` bench learns (``estimate demo corr --subgoals``, default options).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from lfdfuse import learn
from lfdfuse.estimate import sub_step_corrections
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.execute.starts import perturbed_starts
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.read import read_segmented_and_run
from tests.support.corrections import record_correction
from tests.support.generated import THREE_GOALS, TIME_FACTOR
from tests.support.generated_worlds import generate_offroute
from tests.support.offroute import OffRouteCase, run_starts

SEED = 1952
OPTS = EstimateOptions()


def test_a_correction_into_a_branch_past_a_corner_is_a_decision_that_fixes_the_table(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    world = generate_offroute(SEED)
    demo = learn.demonstrate(THREE_GOALS, world=world, folder=tmp_path, name="demo", duration_s=900.0, seed=1)
    run, raw = read_segmented_and_run(demo.segmented)
    max_time_s = float(math.ceil(TIME_FACTOR * demo.duration_s / 10.0) * 10.0)
    case = OffRouteCase(world, THREE_GOALS, max_time_s, ("red", "green", "blue"))
    table = learn.learn([demo.segmented], options=learn.LearnOptions(OPTS, subgoals=True)).table
    start = next(iter(perturbed_starts(world, Pose(*world.start), n=4, rng=np.random.default_rng(SEED))))
    (before,) = run_starts(table, case, starts=[start.as_tuple()], folder=tmp_path, label="before")
    assert not before["completed"], before

    assert raw.pose is not None
    goals_at = [g.stop - 1 for g in run.segments if g.target is not None]
    corr = record_correction(
        table,
        world=world,
        start=start,
        seed=0,
        failed_log=tmp_path / "before-0.mcap",
        teacher_xy=np.asarray(raw.pose)[:, :2],
        goals_at=goals_at,
        max_time_s=max_time_s,
        out=tmp_path / "corr.mcap",
    )
    assert corr is not None

    def learned() -> learn.LearnResult:
        return learn.learn([demo.segmented, corr], options=learn.LearnOptions(OPTS, subgoals=True))

    fixed = learned()
    added = [v.describe() for v in fixed.verdicts if v.describe().startswith("added    reach-green")]
    assert added, [v.describe() for v in fixed.verdicts]
    (after,) = run_starts(fixed.table, case, starts=[start.as_tuple()], folder=tmp_path, label="after")
    assert after["completed"], after

    monkeypatch.setattr(sub_step_corrections, "taken_over_turns", lambda demo, params: [])
    plain = learned()
    assert not any(v.describe().startswith("added") for v in plain.verdicts), "not forced: a corner"
