"""One scripted correction, learned through the sub-goal pooling, fixes a table on a fresh world.

Generated world 1700 (from the range held apart for corrections: seeds 1640 up, never tuned
on): the three-goal demo learned without sub-goals fails from the first of four perturbed starts
(green, then never blue). A scripted person (:mod:`tests.support.corrections`) takes over where
that run left the teacher's path, drives the teacher's path some metres past it and hands back.
The demo and the correction pooled by :func:`lfdfuse.estimate.pooled_subgoals.pool_subgoals` —
the table the correction was recorded against, with its (here: no) decisions — change only rows
the person drove in, and the new table completes from the failed start and at least two of the
three others (measured: all four). The ``corrections`` bench measures the whole of
``estimate demo corr --subgoals`` on many worlds.

Estimated with 128 particles (as tests/execute/test_correction_fixes.py).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from lfdfuse import learn
from lfdfuse.estimate.paper import PFParams
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.pooled_subgoals import pool_subgoals
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.estimate.sub_step_corrections import FurtherDemo
from lfdfuse.estimate.subgoals import track_of
from lfdfuse.execute.starts import perturbed_starts
from lfdfuse.network.table import named_leaf_steps
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.read import network_ticks, read_segmented_and_run
from tests.support.corrections import record_correction
from tests.support.generated import THREE_GOALS, TIME_FACTOR
from tests.support.generated_worlds import generate_offroute
from tests.support.offroute import OffRouteCase, run_starts

SEED = 1700
OPTS = EstimateOptions(seed=0, pf=replace(PFParams(), particles=128), smc=replace(SMCParams(), particles=128))


def test_one_correction_pooled_by_sub_goal_step_fixes_a_fresh_world(tmp_path: Path) -> None:
    world = generate_offroute(SEED)
    demo = learn.demonstrate(THREE_GOALS, world=world, folder=tmp_path, name="demo", duration_s=900.0, seed=1)
    run, raw = read_segmented_and_run(demo.segmented)
    max_time_s = float(math.ceil(TIME_FACTOR * demo.duration_s / 10.0) * 10.0)
    case = OffRouteCase(world, THREE_GOALS, max_time_s, ("red", "green", "blue"))
    table = learn.learn_run(run, options=learn.LearnOptions(OPTS), name=demo.segmented.name).table
    poses = [
        p.as_tuple()
        for p in perturbed_starts(world, Pose(*world.start), n=4, rng=np.random.default_rng(SEED))
    ]
    (before,) = run_starts(table, case, starts=poses[:1], folder=tmp_path, label="before")
    assert not before["completed"], before

    assert raw.pose is not None
    corr = record_correction(
        table,
        world=world,
        start=Pose(*poses[0]),
        seed=0,
        failed_log=tmp_path / "before-0.mcap",
        teacher_xy=np.asarray(raw.pose)[:, :2],
        max_time_s=max_time_s,
        out=tmp_path / "corr.mcap",
    )
    assert corr is not None
    crun, craw = read_segmented_and_run(corr)
    net = network_ticks(corr, crun.t_ns)
    assert net is not None and 0 < int((~net).sum()) < len(net)  # the person drove a part
    res = pool_subgoals(
        first=run,
        first_name=demo.segmented.name,
        paper=table,
        table=table,
        decisions=(),
        others=[FurtherDemo(corr.name, crun, track_of(craw, crun), correction=True)],
        opts=OPTS,
    )
    # only rows the person drove in changed; every other row is bit-identical
    person = np.flatnonzero(crun.informative)
    driven = {(crun.segments[crun.segment_of[i]].target, int(crun.bac[i])) for i in person}
    old = {(s.goal, r.bac): r for _, s in named_leaf_steps(table) for r in s.fusion}
    new = {(s.goal, r.bac): r for _, s in named_leaf_steps(res.table) for r in s.fusion}
    changed = {k for k in new if old.get(k) != new[k]}
    assert changed and changed <= driven, (changed, driven)
    assert all(new[k] == old[k] for k in old.keys() - changed)

    after = run_starts(res.table, case, starts=poses, folder=tmp_path, label="after")
    done = [r["completed"] for r in after]
    assert done[0] and sum(done[1:]) >= 2, after
