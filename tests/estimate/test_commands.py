"""The discrete command model (DESIGN §6): bins, its likelihood, decisions not ticks."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import orjson
import pytest
from scipy.special import i0e

from lfdfuse.estimate.commands import commands_of, decision_steps
from lfdfuse.estimate.model import (
    CommandBins,
    DiscreteRowData,
    FusionModel,
    MixedRowData,
    discrete_log_marginal,
    make_pooled_row,
    make_row,
    row_loglik,
)
from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.estimate.smc import SMCParams, TemperedSMC
from lfdfuse.log.reader import file_info, iter_attachments, iter_raw
from lfdfuse.log.writer import LogWriter
from lfdfuse.network.table import dump_table
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world

KEYS = [0.0, 0.66, -0.66, math.pi / 2, -math.pi / 2]  # straight, arcs, turns in place


def brute_force(
    row_vectors: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    w: np.ndarray,
    model: FusionModel,
    sizes: np.ndarray | None = None,
) -> float:
    """``log p(commands | w)`` by numerical integration over the noise, for one weight vector;
    each step's lapse spread over its command set of ``sizes[t]`` (default: the ``KEYS``)."""
    m = np.full(len(lo), len(KEYS)) if sizes is None else sizes
    x = np.linspace(-math.pi, math.pi, 100_001)
    f = np.einsum("tnc,n->tc", row_vectors, w)
    phi = np.arctan2(f[:, 1], f[:, 0])
    lls = []
    for k in model.discrete_kappas:
        dens = np.exp(k * (np.cos(x) - 1))
        dens /= np.trapezoid(dens, x)
        total = 0.0
        for t in range(len(phi)):
            h = np.remainder(phi[t] + x + math.pi, 2 * math.pi) - math.pi
            p = np.trapezoid(dens * ((h >= lo[t]) & (h < hi[t])), x)
            total += math.log((1 - model.lapse) * p + model.lapse / m[t])
        lls.append(total)
    a = np.array(lls)
    return float(np.log(np.exp(a - a.max()).mean()) + a.max())


@pytest.mark.parametrize("seed", range(3))
def test_the_discrete_likelihood_is_the_probability_of_the_bin(seed: int) -> None:
    rng = np.random.default_rng(seed)
    bins = CommandBins.from_headings(KEYS)
    t, n = 6, 3
    v = rng.normal(size=(t, n, 2))
    h = np.array(KEYS)[rng.integers(0, len(KEYS), t)]
    row = make_row(v, np.stack([np.cos(h), np.sin(h)], -1), bins)
    w = rng.dirichlet(np.ones(n), size=3)
    got = discrete_log_marginal(row, w, FusionModel())  # type: ignore[arg-type]
    want = [brute_force(v, row.lo, row.hi, wi, FusionModel()) for wi in w]  # type: ignore[union-attr]
    assert np.allclose(got, want, atol=2e-3), (got, want)


def test_bins_reach_beyond_the_arcs() -> None:
    b = CommandBins.from_headings(KEYS)
    e = b.edges
    assert e[0] == -math.pi and e[-1] == math.pi and np.all(np.diff(e) > 0)
    # a fused vector pointing backwards asks for a turn in place, in its direction
    from lfdfuse.evaluate.holdout import bin_of

    assert bin_of(b, np.array([2.5, -2.5, 0.1, 0.5])).tolist() == [4, 0, 2, 3]


def test_the_sampler_concentrates_on_weights_that_put_the_commands_in_their_bins() -> None:
    """Two behaviours, one pointing 60° left and one straight: a person pressing arcs left most of
    the time (and straight sometimes) asks for the left one to weigh more, with 'straight' decisions
    bounding it: the posterior mean lands between the bins' edges."""
    rng = np.random.default_rng(4)
    t = 60
    a = np.radians(rng.uniform(40, 80, t))
    v = np.stack([np.stack([np.cos(a), np.sin(a)], -1), np.tile([1.0, 0.0], (t, 1))], axis=1)
    w_true = np.array([0.6, 0.4])
    f = np.einsum("tnc,n->tc", v, w_true)
    phi = np.arctan2(f[:, 1], f[:, 0]) + rng.normal(0, math.radians(5), t)
    bins = CommandBins.from_headings(KEYS)
    from lfdfuse.evaluate.holdout import bin_of

    h = np.array(bins.headings)[bin_of(bins, phi)]
    row = make_row(v, np.stack([np.cos(h), np.sin(h)], -1), bins)
    res = TemperedSMC([row], trials=2, model=FusionModel(), params=SMCParams(particles=600), rng=rng).run()
    mean = res.mean()[:, :2].mean(axis=0)
    assert abs(mean[0] - w_true[0]) < 0.15, mean


def rewrite_on_key_change(src: Path, dst: Path) -> int:
    """The same log with ``/cmd_vel`` sent only when the command changes (as the Neato's teleop does)."""
    meta = file_info(src).metadata.get("lfdfuse", {})
    last = None
    kept = 0
    with LogWriter(dst, metadata=dict(meta)) as log:
        for name, media, data in iter_attachments(src):
            log.attach(name, media, data)
        for raw in iter_raw(src):
            if raw.topic == "/cmd_vel":
                m = orjson.loads(raw.data)
                cmd = (m["linear"]["x"], m["angular"]["z"])
                if cmd == last:
                    continue
                last = cmd
                kept += 1
            log.copy(raw)
    return kept


def test_a_held_command_is_one_decision_however_often_the_log_repeats_it(tmp_path: Path) -> None:
    """A log repeating the held command every tick and one sending it on key change only give
    the same decisions and the same fusion table."""
    demo = tmp_path / "keys.mcap"
    simulate(
        SimulateOptions(
            world=load_world("building"),
            legs=[Leg("red", "keep-left")],
            teacher_name="task",
            duration_s=40.0,
            seed=2,
            keys_period_s=0.6,
        ),
        out=demo,
    )
    sparse = tmp_path / "sparse.mcap"
    kept = rewrite_on_key_change(demo, sparse)
    tables = []
    runs = []
    for src in (demo, sparse):
        seg = tmp_path / f"{src.stem}.seg.mcap"
        segment_file(src, out=seg, lag_s=0.3)
        run = read_segmented(seg)
        runs.append(run)
        table, _, _ = estimate_run(run, opts=EstimateOptions(seed=1))
        tables.append(dump_table(table))
    n = len(runs[0].t_ns)
    assert kept < n / 3  # far fewer messages on key change
    cm = commands_of(runs[0])
    assert cm.mode == "discrete" and cm.decisions is not None
    assert np.array_equal(cm.decisions, commands_of(runs[1]).decisions)
    assert cm.decisions.sum() < 0.25 * n
    assert tables[0] == tables[1]


def test_decisions_are_presses_and_rechecks() -> None:
    from dataclasses import replace

    from lfdfuse.segment.read import SegmentedRun

    n = 30
    h = np.array([0.0] * 12 + [0.66] * 3 + [0.0] * 15)
    inf = np.ones(n, dtype=bool)
    inf[20:22] = False  # a stop
    base = SegmentedRun(
        names=("avoid",),
        t_ns=np.arange(n, dtype=np.int64) * 100_000_000,
        vectors=np.zeros((n, 1, 2)),
        applicable=np.ones((n, 1), dtype=bool),
        goal_met=np.zeros((n, 1), dtype=bool),
        demo=np.stack([np.cos(h), np.sin(h)], -1),
        informative=inf,
        bac=np.ones(n, dtype=np.int64),
        segment_of=np.zeros(n, dtype=np.int64),
        segments=(),
        metadata={},
    )
    assert np.nonzero(decision_steps(base, recheck_s=None))[0].tolist() == [0, 12, 15, 20, 22]
    assert np.nonzero(decision_steps(base, recheck_s=1.0))[0].tolist() == [0, 10, 12, 15, 20, 22]
    assert replace(base, metadata={"segment_commands": "continuous"}) is not None
    assert commands_of(replace(base, metadata={"segment_commands": "continuous"})).mode == "continuous"
    assert commands_of(base).mode == "discrete"  # auto: two distinct headings


def test_commands_and_lag_on_the_command_line(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from lfdfuse.cli.main import app
    from lfdfuse.network.table import load_table
    from tests.conftest import ROOT

    runner = CliRunner()
    demo = ROOT / "sample_logs" / "keep-left-building.mcap"
    seg = tmp_path / "d.seg.mcap"
    bad = runner.invoke(app, ["segment", str(demo), "--lag", "soon", "-o", str(seg)])
    assert bad.exit_code == 2 and "--lag" in bad.output and not seg.exists()  # not a number: usage
    bad = runner.invoke(app, ["segment", str(demo), "--commands", "morse", "-o", str(seg)])
    assert bad.exit_code == 2 and "morse" in bad.output and not seg.exists()  # a bad choice: usage
    res = runner.invoke(app, ["segment", str(demo), "--commands", "discrete", "-o", str(seg)])
    assert res.exit_code == 0, res.output
    meta = read_segmented(seg).metadata
    assert meta["segment_commands"] == "discrete"
    assert float(meta["segment_lag_s"]) >= 0.0  # --lag auto: the best-explaining lag, recorded
    for forced, want in (("auto", "discrete"), ("continuous", "continuous")):
        out = tmp_path / f"{forced}.yaml"
        # a few particles: what is checked is the provenance, not the weights
        args = ["estimate", str(seg), "--commands", forced, "--particles", "32", "-o", str(out)]
        res = runner.invoke(app, args)
        assert res.exit_code == 0, res.output
        by = load_table(out).estimated_by
        assert by["commands"] == want and by["lag_s"] == meta["segment_lag_s"]


def _keyboard_run(
    headings: list[float], *, informative: list[bool] | None = None, bac: list[int] | None = None
):  # noqa: ANN202
    """A 10 Hz segmented run holding ``headings`` (rad), two behaviours pointing ±45°."""
    from lfdfuse.segment.goals import GoalSegment
    from lfdfuse.segment.read import SegmentedRun

    n = len(headings)
    h = np.array(headings)
    vec = np.zeros((n, 2, 2))
    vec[:, 0] = [math.cos(0.8), math.sin(0.8)]
    vec[:, 1] = [math.cos(-0.8), math.sin(-0.8)]
    return SegmentedRun(
        names=("wander_left", "wander_right"),
        t_ns=np.arange(n, dtype=np.int64) * 100_000_000,
        vectors=vec,
        applicable=np.ones((n, 2), dtype=bool),
        goal_met=np.zeros((n, 2), dtype=bool),
        demo=np.stack([np.cos(h), np.sin(h)], -1),
        informative=np.ones(n, dtype=bool) if informative is None else np.array(informative),
        bac=np.full(n, 3, dtype=np.int64) if bac is None else np.array(bac, dtype=np.int64),
        segment_of=np.zeros(n, dtype=np.int64),
        segments=(GoalSegment(0, 0, n, None),),
        metadata={"segment_commands": "discrete"},
    )


def test_the_command_set_has_both_sides_of_the_keyboard() -> None:
    """A person who only turned right in place still had the left key: its bin bounds forward."""
    run = _keyboard_run([0.0] * 10 + [-math.pi / 2] * 10)
    bins = commands_of(run).bins
    assert bins is not None
    assert [round(h, 3) for h in bins.headings] == [-1.571, 0.0, 1.571]
    assert [round(e, 3) for e in bins.edges] == [-3.142, -0.785, 0.785, 3.142]


def test_a_press_undone_within_nudge_s_observes_the_interval_between_the_two_commands() -> None:
    from lfdfuse.estimate.commands import observed_bounds

    arc = 0.66
    tap = _keyboard_run([0.0] * 10 + [-arc] * 3 + [0.0] * 10)  # right arc tapped for 0.3 s
    bins = commands_of(tap).bins
    assert bins is not None
    got = observed_bounds(tap, bins, nudge_s=1.0)
    assert got[10].tolist() == [-arc, 0.0]  # between the arc and straight, not the arc's bin
    assert got[13].tolist() == bins.bounds_of(np.array([0.0]))[0].tolist()  # the return: its own bin
    assert got[0].tolist() == got[13].tolist()
    held = _keyboard_run([0.0] * 10 + [-arc] * 15 + [0.0] * 10)  # held 1.5 s: a change of mind
    assert (
        observed_bounds(held, bins, nudge_s=1.0)[10].tolist() == bins.bounds_of(np.array([-arc]))[0].tolist()
    )
    assert (
        observed_bounds(tap, bins, nudge_s=None)[10].tolist() == bins.bounds_of(np.array([-arc]))[0].tolist()
    )
    stop = [True] * 23
    stop[13] = False  # a stop, then straight again: no nudge (the press was not undone)
    stopped = _keyboard_run([0.0] * 10 + [-arc] * 3 + [0.0] * 10, informative=stop)
    assert (
        observed_bounds(stopped, bins, nudge_s=1.0)[10].tolist()
        == bins.bounds_of(np.array([-arc]))[0].tolist()
    )


def test_a_situation_met_only_between_decisions_is_no_row() -> None:
    """A BAC whose informative ticks hold no decision (met while a key was held) has no
    observation of the discrete model: the table skips it rather than failing."""
    h = [0.0] * 8 + [0.66] * 6 + [0.0] * 16
    bac = [3] * 20 + [1] * 4 + [3] * 6  # BAC 1 only while straight is held, between re-checks
    run = _keyboard_run(h, bac=bac)
    decided = commands_of(run).decisions
    assert decided is not None and not decided[20:24].any()
    table, groups, skipped = estimate_run(run, opts=EstimateOptions(seed=0))
    assert (groups, skipped) == (2, 1)
    assert [r.bac for r in table.network.steps[0].fusion] == [3]


# ------------------------------------------------------------------------------ pooled demos, each its own model


def continuous_brute_force(
    row_vectors: np.ndarray, demo: np.ndarray, w: np.ndarray, model: FusionModel
) -> float:
    """``log p(headings | w)`` of the continuous model: von Mises errors, κ averaged over its nodes."""
    f = np.einsum("tnc,n->tc", row_vectors, w)
    err = np.arctan2(f[:, 1], f[:, 0]) - np.arctan2(demo[:, 1], demo[:, 0])
    # log I₀(κ) = log i0e(κ) + κ: finite at the sharpest nodes
    lls = [
        float(np.sum(k * (np.cos(err) - 1) - math.log(2 * math.pi) - math.log(i0e(k)))) for k in model.kappas
    ]
    a = np.array(lls)
    return float(np.log(np.exp(a - a.max()).mean()) + a.max())


def pooled_row_case(seed: int, sizes: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Random behaviour vectors, headings and observed bins of steps from demos whose command
    sets have ``sizes`` (0: a continuous demo's step)."""
    rng = np.random.default_rng(seed)
    t, n = len(sizes), 3
    v = rng.normal(size=(t, n, 2))
    h = np.array(KEYS)[rng.integers(0, len(KEYS), t)] + np.where(
        np.array(sizes) == 0, rng.normal(0, 0.3, t), 0.0
    )
    demo = np.stack([np.cos(h), np.sin(h)], -1)
    bounds = CommandBins.from_headings(KEYS).bounds_of(h)
    return v, demo, bounds, np.array(sizes)


@pytest.mark.parametrize("seed", range(3))
def test_pooled_keyboards_keep_their_own_command_sets(seed: int) -> None:
    """Two keyboard demos with command sets of 5 and 3 keys, pooled: each decision's lapse is
    spread over its own demo's keys (numerical integration agrees)."""
    v, demo, bounds, sizes = pooled_row_case(seed, [5, 5, 3, 3, 3, 5])
    row = make_pooled_row(v, demo, bounds, sizes)
    assert isinstance(row, DiscreteRowData)
    w = np.random.default_rng(seed + 10).dirichlet(np.ones(3), size=3)
    got = row_loglik(row, w, FusionModel())
    want = [brute_force(v, bounds[:, 0], bounds[:, 1], wi, FusionModel(), sizes) for wi in w]
    assert np.allclose(got, want, atol=2e-3), (got, want)


@pytest.mark.parametrize("seed", range(3))
def test_a_row_pooling_a_scripted_demo_and_a_keyboard_reads_each_by_its_own_model(seed: int) -> None:
    """A scripted demo's steps (continuous) and a person's keyboard decisions in one row: the
    likelihood is the product of each read by its own model, each with its own noise."""
    sizes = [0, 5, 0, 0, 5, 5, 0]
    v, demo, bounds, arr = pooled_row_case(seed, sizes)
    row = make_pooled_row(v, demo, bounds, arr)
    assert isinstance(row, MixedRowData) and row.steps == len(sizes)
    w = np.random.default_rng(seed + 20).dirichlet(np.ones(3), size=3)
    model = FusionModel()
    cont, disc = arr == 0, arr > 0
    want = [
        continuous_brute_force(v[cont], demo[cont], wi, model)
        + brute_force(v[disc], bounds[disc, 0], bounds[disc, 1], wi, model, arr[disc])
        for wi in w
    ]
    assert np.allclose(row_loglik(row, w, model), want, atol=2e-3), (row_loglik(row, w, model), want)


@pytest.mark.parametrize("seed", range(3))
def test_pooled_demos_of_one_command_model_are_read_as_one_demo(seed: int) -> None:
    """Demos that share a command set pool into exactly the row one demo of all their steps gives
    (bit for bit), and continuous demos into the continuous row."""
    v, demo, bounds, sizes = pooled_row_case(seed, [5] * 6)
    w = np.random.default_rng(seed).dirichlet(np.ones(3), size=4)
    same = make_row(v, demo, CommandBins.from_headings(KEYS), bounds)
    assert np.array_equal(
        row_loglik(make_pooled_row(v, demo, bounds, sizes), w, FusionModel()),
        row_loglik(same, w, FusionModel()),
    )
    zeros = np.zeros(6, dtype=np.int64)
    assert np.array_equal(
        row_loglik(make_pooled_row(v, demo, bounds, zeros), w, FusionModel()),
        row_loglik(make_row(v, demo), w, FusionModel()),
    )
