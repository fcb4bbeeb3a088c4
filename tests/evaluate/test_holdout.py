"""Held-out evaluation: exact on noise-free fusions, honest baselines, the DESIGN §12 JSON."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.errors import ConfigError
from lfdfuse.evaluate.holdout import METHODS, evaluate, slice_run
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.read import SegmentedRun

NAMES = ("avoid", "wander", "wall_attract_left", "wall_attract_right")


def synthetic(n: int, seed: int, *, noise_deg: float = 0.0, goal_at: int | None = None) -> SegmentedRun:
    """A segmented run whose demonstrated heading is a known fusion (per BAC) of random vectors."""
    rng = np.random.default_rng(seed)
    ang = rng.uniform(-1.2, 1.2, (n, len(NAMES)))
    vec = np.stack([np.cos(ang), np.sin(ang)], axis=-1) * rng.uniform(0.3, 1.0, (n, len(NAMES), 1))
    app = np.ones((n, len(NAMES)), bool)
    app[: n // 2, 3] = False  # two BACs
    vec[~app] = 0.0
    bits = (app * (1 << np.arange(len(NAMES)))).sum(axis=1)
    weights = {int(b): rng.dirichlet(np.ones(len(NAMES))) for b in np.unique(bits)}
    fused = np.stack([vec[i].T @ weights[int(bits[i])] for i in range(n)])
    head = np.arctan2(fused[:, 1], fused[:, 0]) + np.radians(noise_deg) * rng.standard_normal(n)
    segs = (GoalSegment(0, 0, n, None),)
    seg_of = np.zeros(n, np.int64)
    if goal_at is not None:
        segs = (GoalSegment(0, 0, goal_at, "attract_red"), GoalSegment(1, goal_at, n, None))
        seg_of[goal_at:] = 1
    return SegmentedRun(
        names=NAMES,
        t_ns=np.arange(n, dtype=np.int64) * 100_000_000,
        vectors=vec,
        applicable=app,
        goal_met=np.zeros_like(app),
        demo=np.stack([np.cos(head), np.sin(head)], axis=1),
        informative=np.ones(n, bool),
        bac=bits.astype(np.int64),
        segment_of=seg_of,
        segments=segs,
        metadata={},
    )


def test_a_noise_free_fusion_is_predicted_exactly_and_beats_the_baselines() -> None:
    run = synthetic(600, 1)
    ev = evaluate(run, holdout=0.3)
    m = {k: v.heading_error_deg for k, v in ev.methods.items()}
    assert m["fused"] < 1.0 and m["oracle"] < 1.0 and m["nnls"] < 1.0
    assert m["straight"] > 10 * m["fused"] and m["arbitration"] > 5 * m["fused"]
    assert ev.train_steps == 420 and ev.test_steps == 180


def test_noise_sets_the_floor_and_the_interval_covers_the_mean() -> None:
    ev = evaluate(synthetic(800, 2, noise_deg=8.0), holdout=0.3)
    floor = 8.0 * math.sqrt(2 / math.pi)  # mean |N(0, σ)|
    for name, s in ev.methods.items():
        assert s.ci95_deg[0] <= s.heading_error_deg <= s.ci95_deg[1], name
    assert abs(ev.methods["fused"].heading_error_deg - floor) < 2.0
    assert ev.methods["oracle"].heading_error_deg < floor + 1.5


def test_goal_segments_that_training_never_reached_use_default_weights() -> None:
    run = synthetic(500, 3, goal_at=450)  # the second goal segment lies wholly in the held-out part
    ev = evaluate(run, holdout=0.3)
    assert math.isfinite(ev.methods["fused"].heading_error_deg)


@settings(max_examples=30, deadline=None)
@given(st.integers(20, 200), st.integers(1, 199), st.integers(0, 10))
def test_slices_partition_a_run(n: int, cut: int, goal: int) -> None:
    cut = min(cut, n - 1)
    run = synthetic(n, 0, goal_at=min(goal + 5, n - 1))
    a, b = slice_run(run, 0, cut), slice_run(run, cut, n)
    assert np.array_equal(np.concatenate([a.demo, b.demo]), run.demo)
    assert np.array_equal(np.concatenate([a.bac, b.bac]), run.bac)
    assert sum(s.stop - s.start for s in a.segments) == cut
    assert sum(s.stop - s.start for s in b.segments) == n - cut


@pytest.mark.parametrize("holdout", [0.0, 1.0, -0.2, math.nan])
def test_bad_holdout_is_a_clear_error(holdout: float) -> None:
    with pytest.raises(ConfigError, match="holdout"):
        evaluate(synthetic(100, 0), holdout=holdout)


def test_cli_writes_the_design_json(tmp_path: Path, keep_left_segmented: Path) -> None:
    seg = keep_left_segmented
    out = tmp_path / "eval.json"
    res = CliRunner().invoke(app, ["evaluate", str(seg), "--holdout", "0.3", "--json", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    assert set(data["methods"]) == set(METHODS)
    assert data["train_steps"] > 2 * data["test_steps"] > 0
    for s in data["methods"].values():
        assert 0.0 <= s["heading_error_deg"] <= 180.0
    for name in METHODS:
        assert name in res.output
    for value in ("1.5", "0", "nan"):
        bad = CliRunner().invoke(app, ["evaluate", str(seg), "--holdout", value])
        assert bad.exit_code == 2 and "--holdout" in bad.output and "fraction" in bad.output


def test_the_oracle_reads_held_out_decisions_in_the_persons_command_set() -> None:
    """A keyboard demo whose held-out part holds one command (straight): the oracle is fitted in the
    command set of the whole demo (straight's bin is ±45° between the turns in place), not in the
    one command the part holds (one bin, the whole circle: every decision in it, the oracle the
    prior). Behaviours point 0° and 120°: straight decisions say the first carries the weight."""
    n = 400
    h = np.zeros(n)
    h[100:160] = -math.pi / 2  # a turn in place to the right while training; the rest straight
    vec = np.zeros((n, 2, 2))
    vec[:, 0] = [1.0, 0.0]
    vec[:, 1] = [math.cos(2.1), math.sin(2.1)]
    run = SegmentedRun(
        names=("wander_left", "wander_right"),
        t_ns=np.arange(n, dtype=np.int64) * 100_000_000,
        vectors=vec,
        applicable=np.ones((n, 2), bool),
        goal_met=np.zeros((n, 2), bool),
        demo=np.stack([np.cos(h), np.sin(h)], axis=1),
        informative=np.ones(n, bool),
        bac=np.full(n, 3, np.int64),
        segment_of=np.zeros(n, np.int64),
        segments=(GoalSegment(0, 0, n, None),),
        metadata={"segment_commands": "discrete"},
    )
    ev = evaluate(run, holdout=0.3)
    assert ev.commands == "discrete" and ev.held_out_headings == 1
    # the prior's mean (equal weights) points 60° off straight; straight's bin holds it within 45°
    assert ev.methods["oracle"].heading_error_deg < 30.0, ev.methods["oracle"]
