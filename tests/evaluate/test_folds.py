"""Blocked k-fold over the informative decisions: the folds' laws, every fold fitted without its own
steps, the too-few line, and the scores on a known fusion."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import lfdfuse.evaluate.folds as folds_mod
from lfdfuse.cli.main import app
from lfdfuse.errors import ConfigError
from lfdfuse.estimate.commands import commands_of
from lfdfuse.estimate.keys import KeyResponse, key_heading
from lfdfuse.estimate.model import CommandBins, FusionModel
from lfdfuse.estimate.pipeline import EstimateOptions, Method
from lfdfuse.evaluate.folds import (
    KFOLD_METHODS,
    MIN_DECISIONS,
    evaluate_folds,
    fold_ranges,
    informative_decisions,
)
from lfdfuse.evaluate.holdout import evaluate
from lfdfuse.network.table import FusionTable, Network, default_weights_for
from lfdfuse.segment.read import SegmentedRun
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg, parse_style
from lfdfuse.world.model import load_world
from tests.evaluate.test_holdout import synthetic


@st.composite
def decisions_in_steps(draw: st.DrawFn) -> tuple[np.ndarray, int, int]:
    folds = draw(st.integers(2, 8))
    n = draw(st.integers(folds, 300))
    k = draw(st.integers(folds, n))
    chosen = draw(st.lists(st.integers(0, n - 1), min_size=k, max_size=k, unique=True))
    return np.array(sorted(chosen), dtype=np.int64), n, folds


@given(decisions_in_steps())
@settings(max_examples=80, deadline=None)
def test_folds_partition_the_steps_into_contiguous_blocks_of_decisions(
    case: tuple[np.ndarray, int, int],
) -> None:
    decisions, n, folds = case
    ranges = fold_ranges(decisions, n, folds)
    assert len(ranges) == folds
    # contiguous and a partition: each range starts where the last stopped, from 0 to n
    assert ranges[0][0] == 0 and ranges[-1][1] == n
    assert all(a[1] == b[0] for a, b in zip(ranges, ranges[1:], strict=False))
    assert all(a < b for a, b in ranges)
    counts = [int(((decisions >= a) & (decisions < b)).sum()) for a, b in ranges]
    assert sum(counts) == len(decisions) and min(counts) >= 1
    assert max(counts) - min(counts) <= 1  # nearly equal blocks
    for a, _ in ranges[1:]:
        assert a in decisions  # a fold (but the first) starts at its first decision


def test_too_few_decisions_for_the_folds_is_an_error() -> None:
    with pytest.raises(ConfigError, match="cannot fill 5 folds"):
        fold_ranges(np.arange(4), 10, 5)
    with pytest.raises(ConfigError, match="at least 2"):
        fold_ranges(np.arange(4), 10, 1)


def _recording_fits(
    monkeypatch: pytest.MonkeyPatch,
) -> list[tuple[str, np.ndarray]]:
    """Replace the estimator by one that records which steps each fit could learn from (its
    informative mask) and returns the default table: the folds' plumbing, not the estimator."""
    seen: list[tuple[str, np.ndarray]] = []

    def fake(
        part: SegmentedRun, *, opts: EstimateOptions, name: str, **_: Any
    ) -> tuple[FusionTable, int, int]:
        seen.append((name, part.informative.copy()))
        return FusionTable(part.names, default_weights_for(part.names), Network("x", ())), 0, 0

    monkeypatch.setattr(folds_mod, "estimate_run", fake)
    return seen


@given(st.integers(20, 200), st.integers(2, 6), st.integers(0, 2**16))
@settings(max_examples=40, deadline=None)
def test_every_fold_is_fitted_without_its_own_steps(n: int, folds: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    run = synthetic(n, seed % 7)
    informative = rng.random(n) < 0.8
    informative[rng.choice(n, size=MIN_DECISIONS, replace=False)] = True  # enough decisions
    run = replace(run, informative=informative)
    with pytest.MonkeyPatch.context() as mp:
        seen = _recording_fits(mp)
        ev = evaluate_folds(run, folds=folds, seed=0, opts=EstimateOptions(commands="continuous"))
    ranges = fold_ranges(np.nonzero(informative)[0], n, folds)
    assert len(seen) == 4 * folds  # fused, nnls, arbitration, oracle per fold
    for j, (a, b) in enumerate(ranges):
        inside = np.zeros(n, bool)
        inside[a:b] = True
        for name, mask in seen[4 * j : 4 * j + 4]:
            if name == "oracle":  # the floor: fitted on the fold itself
                assert np.array_equal(mask, informative & inside)
            else:  # fitted on every other fold's steps, none of its own
                assert not (mask & inside).any()
                assert np.array_equal(mask, informative & ~inside)
    # every informative step is scored once, by the fit that did not see it
    assert ev.test_steps == int(informative.sum())
    assert all(len(s.fold_errors_deg or ()) == folds for s in ev.methods.values())


def test_a_noise_free_fusion_is_predicted_exactly_in_every_fold() -> None:
    run = synthetic(240, 3)
    ev = evaluate_folds(run, seed=0)
    m = {k: v.heading_error_deg for k, v in ev.methods.items()}
    assert list(ev.methods) == [k for k in KFOLD_METHODS if k != "bc"]  # no scan features: no bc
    assert m["fused"] < 0.5 and m["oracle"] < 0.5, m
    assert m["fused"] < m["straight"] - 5 and m["fused"] < m["arbitration"], m
    assert max(ev.methods["fused"].fold_errors_deg or ()) < 1.0
    assert ev.split == "kfold" and ev.informative_decisions == 240 and ev.test_steps == 240
    data = ev.to_dict()
    assert data["holdout"] is None and data["folds"] == 5
    assert len(data["methods"]["fused"]["fold_errors_deg"]) == 5
    json.dumps(data, allow_nan=False)  # strict JSON


def test_a_drive_that_ends_standing_still_is_scored() -> None:
    """The time split holds out the still end and has nothing to score; the folds do not."""
    run = synthetic(300, 4)
    still = run.informative.copy()
    still[200:] = False
    run = replace(run, informative=still)
    with pytest.raises(ConfigError, match="too few"):
        evaluate(run, holdout=0.3)
    ev = evaluate_folds(run, seed=0, opts=EstimateOptions(method=Method.NNLS))
    m = {k: v.heading_error_deg for k, v in ev.methods.items()}
    assert ev.test_steps == 200 and m["fused"] < 5.0 and m["fused"] < m["straight"] - 10, m


@pytest.mark.parametrize("n", [MIN_DECISIONS - 1, MIN_DECISIONS])
def test_fewer_than_twenty_decisions_says_how_many_it_has_and_needs(n: int) -> None:
    run = synthetic(n, 5)
    fast = EstimateOptions(method=Method.NNLS)
    if n < MIN_DECISIONS:
        with pytest.raises(ConfigError) as err:
            evaluate_folds(run, opts=fast)
        line = str(err.value)
        assert "\n" not in line
        assert f"{n} informative" in line and f"need {MIN_DECISIONS}" in line, line
    else:
        assert evaluate_folds(run, opts=fast).test_steps == n


def test_the_cli_says_in_one_line_why_a_short_demo_is_not_scored(tmp_path: Path) -> None:
    """A 1.5 s demo through the real command: one `error:` line with its count, exit 1 (the
    contract for a log that cannot be evaluated), no traceback."""
    demo = tmp_path / "short.mcap"
    opts = SimulateOptions(
        world=load_world("corridor"),
        legs=[Leg(None, parse_style("keep-left"))],
        teacher_name="keep-left",
        duration_s=1.5,
        seed=0,
    )
    simulate(opts, out=demo)
    res = CliRunner().invoke(app, ["evaluate", str(demo)])
    assert res.exit_code == 1, res.output
    errors = [line for line in res.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1, res.output
    assert "too few decisions to score:" in errors[0] and f"need {MIN_DECISIONS}" in errors[0], errors
    assert "Traceback" not in res.output


def _run_twice(f: Callable[[], Any]) -> tuple[Any, Any]:
    return f(), f()


def test_behaviour_cloning_is_deterministic_and_learns_what_the_scan_says() -> None:
    """bc, from scan features that say the heading (a wall at a sector's range), is near exact, and
    two evaluations give the same bytes."""
    run = synthetic(200, 6)
    rng = np.random.default_rng(0)
    heading = rng.choice([-0.6, 0.0, 0.6], size=200)
    run = replace(run, demo=np.stack([np.cos(heading), np.sin(heading)], axis=1))
    features = np.full((200, 12), 4.0)
    features[:, 5] = 1.0 + heading + rng.normal(0, 0.01, 200)  # what the scan sees says the heading
    fast = EstimateOptions(method=Method.NNLS)
    a, b = _run_twice(lambda: evaluate_folds(run, seed=1, features=features, opts=fast).to_dict())
    assert json.dumps(a) == json.dumps(b)
    assert a["methods"]["bc"]["heading_error_deg"] < 1.0, a["methods"]["bc"]
    assert list(a["methods"]) == list(KFOLD_METHODS)


def test_command_accuracy_is_scored_per_fold_on_a_keyboard_demo() -> None:
    """A discrete demo (two keys, switched every 20 steps): the decisions are what is cut into
    folds, and every decision is scored once."""
    n = 400
    run = synthetic(n, 7)
    key = np.where((np.arange(n) // 20) % 2 == 0, 0.0, 0.8)
    run = replace(
        run,
        demo=np.stack([np.cos(key), np.sin(key)], axis=1),
        metadata={"segment_commands": "discrete"},
    )
    ev = evaluate_folds(run, seed=0, opts=EstimateOptions(method=Method.NNLS))
    assert ev.commands == "discrete" and ev.test_decisions is not None
    # key changes every 20 steps (2 s) and a 1 s recheck: 2 decisions per held key
    assert ev.informative_decisions == 2 * (n // 20) and ev.test_decisions == ev.informative_decisions
    acc = ev.methods["straight"].command_accuracy
    assert acc is not None and 0.0 <= acc <= 1.0 and not math.isnan(acc)


def test_a_keyboard_demo_is_predicted_as_key_presses_fitted_on_the_training_decisions(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A person of the discrete model (the key whose bin holds a known fusion's heading): every
    fit's key response is fitted on the decisions of its own training steps only (the oracle's:
    its fold's), fused's is recorded per fold, and the keys and headings read from the fits
    predict the person far better than 'straight'."""
    n = 300
    run = synthetic(n, 5)
    keyboard = CommandBins.from_headings([-1.57, -0.66, 0.0, 0.66, 1.57])
    h = key_heading(keyboard, np.arctan2(run.demo[:, 1], run.demo[:, 0]))
    run = replace(
        run, demo=np.stack([np.cos(h), np.sin(h)], axis=1), metadata={"segment_commands": "discrete"}
    )
    sizes: list[int] = []
    real = folds_mod.fit_key_response

    def spy(bins: CommandBins, heading: np.ndarray, keys: np.ndarray, model: FusionModel) -> KeyResponse:
        sizes.append(len(keys))
        return real(bins, heading, keys, model)

    monkeypatch.setattr(folds_mod, "fit_key_response", spy)
    opts = EstimateOptions(method=Method.NNLS)
    ev = evaluate_folds(run, seed=0, opts=opts)
    cm = commands_of(run)
    assert cm.decisions is not None
    units = informative_decisions(run, cm)
    expected = []
    for a, b in fold_ranges(units, n, 5):
        inside = int(((units >= a) & (units < b)).sum())
        expected += [len(units) - inside] * 3 + [inside]  # fused, nnls, arbitration; the oracle
    assert sizes == expected
    assert ev.keys is not None and len(ev.keys["fused"]) == 5
    assert all(r["sigma_deg"] < 10.0 for r in ev.keys["fused"]), ev.keys  # the fusion tells the key
    m = ev.methods
    f, s = m["fused"].command_accuracy, m["straight"].command_accuracy
    assert f is not None and s is not None and f > 0.9 and f > s + 0.3, (f, s)
    assert m["fused"].heading_error_deg < 3.0 < m["straight"].heading_error_deg, m
    assert ev.to_dict()["keys"] == ev.keys
