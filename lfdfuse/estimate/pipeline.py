"""``estimate``: from a segmented demo to a fusion table (paper Sections IV-B and IV-C).

For every goal segment and every BAC inside it, the informative steps are pooled into a *group*
and the weights of the applicable behaviours are estimated with the chosen method. One network
step per goal segment, in order, named after its goal; a trailing part with no goal reached
becomes a step with goal null.

``pf`` samples every group of the run (and the default-weight fits) in one batched tempered SMC
pass (:mod:`lfdfuse.estimate.smc`) — ``--trials K`` included. A group with one applicable
behaviour gets weight 1; a group with no informative step is skipped (its BAC falls back to the
default weights).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.baselines import angle_errors, arbitration_weights, nnls_weights
from lfdfuse.estimate.identifiability import identifiable
from lfdfuse.estimate.model import FusionModel, row_data, sum_cos
from lfdfuse.estimate.paper import PFParams, normalise, run_filter
from lfdfuse.estimate.smc import SMCParams, TemperedSMC
from lfdfuse.network.table import FusionRow, FusionTable, Network, Step, default_weights_for, write_table
from lfdfuse.segment.read import SegmentedRun, read_segmented

Method = Literal["pf", "paper", "nnls", "arbitration"]
METHODS: tuple[str, ...] = ("pf", "paper", "nnls", "arbitration")


@dataclass(frozen=True)
class EstimateOptions:
    method: Method = "pf"
    trials: int = 1
    seed: int = 0
    model: FusionModel = field(default_factory=FusionModel)  # pf: prior and noise model
    smc: SMCParams = field(default_factory=SMCParams)  # pf: the sampler
    pf: PFParams = field(default_factory=PFParams)  # paper: the published filter
    min_samples: int = 30  # rows with fewer informative steps are flagged low_samples


@dataclass(frozen=True)
class RowEstimate:
    """One group's estimate over its ``n`` applicable behaviours."""

    weights: np.ndarray  # (n,) summing to 1
    std: np.ndarray  # (n,) posterior std (pf), else the spread over trials
    trial_std: np.ndarray | None  # (n,) spread of the trials' estimates, when trials > 1
    identifiable: bool | None  # pf only: False when the prior decides some direction


@dataclass(frozen=True)
class Group:
    """The pooled steps of one (goal segment, BAC)."""

    segment: int
    bac: int
    behaviors: tuple[int, ...]  # indices of the applicable behaviours
    steps: np.ndarray  # indices into the run


def groups_of(run: SegmentedRun) -> list[Group]:
    """Every (goal segment, BAC) with its informative steps, in segment order then BAC order."""
    out = []
    k = len(run.names)
    for seg in run.segments:
        sl = np.arange(seg.start, seg.stop)
        for b in sorted(set(run.bac[sl].tolist())):
            app = tuple(i for i in range(k) if b >> i & 1)
            if not app:
                continue
            steps = sl[(run.bac[sl] == b) & run.informative[sl]]
            out.append(Group(seg.index, int(b), app, steps))
    return out


#: chains (rows × trials) per sampler pass: bounds the sampler's memory (chains × particles × κ nodes)
CHAIN_BATCH = 128


def _pf_rows(
    problems: Sequence[tuple[np.ndarray, np.ndarray]], *, opts: EstimateOptions, rng: np.random.Generator
) -> list[RowEstimate]:
    """One batched SMC pass over every problem with ≥ 2 behaviours and ≥ 1 step."""
    out: list[RowEstimate | None] = [None] * len(problems)
    todo = []
    for i, (vec, _demo) in enumerate(problems):
        n = vec.shape[1]
        if n == 1:
            out[i] = RowEstimate(np.ones(1), np.zeros(1), np.zeros(1) if opts.trials > 1 else None, True)
        elif vec.shape[0] == 0:  # no data: the prior, which pins nothing
            prior_sd = math.sqrt((n - 1) / (n * n * (n * opts.model.alpha + 1.0)))
            out[i] = RowEstimate(np.full(n, 1.0 / n), np.full(n, prior_sd), None, False)
        else:
            todo.append(i)
    k = opts.trials
    # rows are sampled in batches: the sampler's arrays grow with the rows it holds, and an
    # hour-long demo has hundreds of rows (a batch is one pass for any ordinary demo)
    per_pass = max(1, CHAIN_BATCH // k)
    for b in range(0, len(todo), per_pass):
        batch = todo[b : b + per_pass]
        datas = [row_data(*problems[i]) for i in batch]
        smc = TemperedSMC(datas, trials=k, model=opts.model, params=opts.smc, rng=rng)
        res = smc.run()
        means, covs, particles = res.mean(), res.cov(), res.weights
        for j, i in enumerate(batch):
            n = problems[i][0].shape[1]
            cov = covs[j * k : (j + 1) * k, :n, :n].mean(axis=0)
            pinned = identifiable(cov, opts.model)
            if pinned:
                # the data pins the row: report the posterior mode (the most likely posterior
                # particle), which lands as close to the truth as a heading fit; a posterior mean
                # is pulled off the simplex's edges, where sparse rows live, by the posterior's width
                w = particles[j * k : (j + 1) * k, :, :n]  # (K, M, n)
                best = np.array([trial[int(np.argmax(sum_cos(datas[j], trial)))] for trial in w])  # (K, n)
            else:
                # the data leaves a direction open: the posterior mean, where the prior decides it
                best = means[j * k : (j + 1) * k, :n]
            out[i] = RowEstimate(
                normalise(best.mean(axis=0)),
                np.sqrt(np.maximum(np.diag(cov), 0.0)),
                best.std(axis=0) if k > 1 else None,
                pinned,
            )
    return [r for r in out if r is not None]


def _other_row(
    vectors: np.ndarray, demo: np.ndarray, *, opts: EstimateOptions, rng: np.random.Generator
) -> RowEstimate:
    t, n, _ = vectors.shape
    k = opts.trials
    if n == 1:
        return RowEstimate(np.ones(1), np.zeros(1), np.zeros(1) if k > 1 else None, None)
    if opts.method == "paper":
        res = run_filter(vectors, demo, trials=k, rng=rng, params=opts.pf)
        spread = res.weights.std(axis=0) if k > 1 else None
        return RowEstimate(normalise(res.weights.mean(axis=0)), res.spread.mean(axis=0), spread, None)
    fit: Callable[[np.ndarray, np.ndarray], np.ndarray] = (
        nnls_weights if opts.method == "nnls" else arbitration_weights
    )
    if k == 1:
        return RowEstimate(normalise(fit(vectors, demo)), np.zeros(n), None, None)
    boots = np.array(
        [normalise(fit(vectors[idx], demo[idx])) for idx in (rng.integers(0, t, t) for _ in range(k))]
    )
    return RowEstimate(normalise(boots.mean(axis=0)), boots.std(axis=0), boots.std(axis=0), None)


def estimate_groups(
    problems: Sequence[tuple[np.ndarray, np.ndarray]], *, opts: EstimateOptions, rng: np.random.Generator
) -> list[RowEstimate]:
    """Estimates for groups given as ``(vectors (T, n, 2), demo (T, 2))`` pairs, in order."""
    if opts.method not in METHODS:
        raise ConfigError(f"unknown method {opts.method!r} (valid: {', '.join(METHODS)})")
    if opts.method == "pf":
        return _pf_rows(problems, opts=opts, rng=rng)
    return [_other_row(v, d, opts=opts, rng=rng) for v, d in problems]


def estimate_group(
    vectors: np.ndarray, demo: np.ndarray, *, opts: EstimateOptions, rng: np.random.Generator
) -> RowEstimate:
    """The estimate of one group: ``vectors (T, n, 2)``, ``demo (T, 2)``."""
    return estimate_groups([(vectors, demo)], opts=opts, rng=rng)[0]


@dataclass(frozen=True)
class EstimateResult:
    table: FusionTable
    out: str
    groups: int
    skipped: int  # groups with no informative step


def step_names(goals: list[str | None]) -> list[str]:
    names: list[str] = []
    for g in goals:
        base = f"reach-{g}" if g else "free"
        name, i = base, 2
        while name in names:
            name, i = f"{base}-{i}", i + 1
        names.append(name)
    return names


def _default_masks(run: SegmentedRun, opts: EstimateOptions) -> tuple[list[int], list[np.ndarray | None]]:
    """The goal-free behaviours, and per default fit (table, then each step) its steps or None.

    The default weights meet an unseen situation in the demonstrated manner: the goal-free
    behaviours (all but ``attract_*``) fitted over every informative step of the demo (the
    table's) or of one goal segment (that step's). Too few steps: None (safe wandering for the
    table, the table's default for a step).
    """
    idx = [i for i, n in enumerate(run.names) if not n.startswith("attract_")]
    base = run.informative & run.applicable[:, idx].any(axis=1) if idx else np.zeros_like(run.informative)
    masks: list[np.ndarray | None] = []
    for within in [None, *(run.segment_of == s.index for s in run.segments)]:
        if within is not None and int((within & run.informative).sum()) < opts.min_samples:
            masks.append(None)
            continue
        mask = base if within is None else base & within
        steps = np.nonzero(mask)[0]
        masks.append(steps if len(idx) and len(steps) >= opts.min_samples else None)
    return idx, masks


def estimate_run(
    run: SegmentedRun,
    *,
    opts: EstimateOptions,
    name: str = "demo",
    progress: Callable[[float, float], None] | None = None,
) -> tuple[FusionTable, int, int]:
    """The fusion table of a segmented run; returns it with the group and skipped counts."""
    if opts.method not in METHODS:
        raise ConfigError(f"unknown method {opts.method!r} (valid: {', '.join(METHODS)})")
    if opts.trials < 1 or opts.pf.particles < 1 or opts.smc.particles < 1:
        raise ConfigError("--trials and --particles must be at least 1")
    groups = groups_of(run)
    live = [g for g in groups if len(g.steps)]
    problems = [(run.vectors[g.steps][:, list(g.behaviors), :], run.demo[g.steps]) for g in live]
    idx, masks = _default_masks(run, opts)
    # a step's default fit over the same steps as the table's is the same fit: do it once
    uniq: list[np.ndarray] = []
    slot: list[int | None] = []
    for m in masks:
        if m is None:
            slot.append(None)
            continue
        hit = next((j for j, u in enumerate(uniq) if len(u) == len(m) and np.array_equal(u, m)), None)
        if hit is None:
            uniq.append(m)
            hit = len(uniq) - 1
        slot.append(hit)
    problems += [(run.vectors[s][:, idx, :], run.demo[s]) for s in uniq]
    rng = np.random.default_rng([opts.seed, len(run.t_ns)])
    est = estimate_groups(problems, opts=opts, rng=rng)
    rows: dict[int, list[FusionRow]] = {s.index: [] for s in run.segments}
    for g, e, (vec, demo) in zip(live, est, problems, strict=False):
        err = float(np.degrees(angle_errors(vec, demo, e.weights).mean()))
        names = [run.names[i] for i in g.behaviors]
        rows[g.segment].append(
            FusionRow(
                bac=g.bac,
                weights={nm: float(x) for nm, x in zip(names, e.weights, strict=True)},
                std={nm: float(x) for nm, x in zip(names, e.std, strict=True)},
                samples=int(len(g.steps)),
                fit_error_deg=err if math.isfinite(err) else 180.0,
                low_samples=len(g.steps) < opts.min_samples,
                trial_std=None
                if e.trial_std is None
                else {nm: float(x) for nm, x in zip(names, e.trial_std, strict=True)},
                identifiable=e.identifiable,
            )
        )
    if progress is not None:
        progress(1.0, 1.0)
    fits = est[len(live) :]

    def default(j: int | None) -> dict[str, float] | None:
        if j is None:
            return None
        out = {
            run.names[i]: round(float(x), 4) for i, x in zip(idx, fits[j].weights, strict=True) if x >= 1e-4
        }
        return out or None

    goals = [
        s.goal[len("attract_") :] if s.goal and s.goal.startswith("attract_") else None for s in run.segments
    ]
    steps = tuple(
        Step(nm, goal, tuple(rows[s.index]), None, default(slot[1 + i]))
        for i, (nm, goal, s) in enumerate(zip(step_names(goals), goals, run.segments, strict=True))
    )
    by: dict[str, object] = {"method": opts.method, "trials": opts.trials, "seed": opts.seed, "source": name}
    if opts.method == "pf":
        by |= {
            "particles": opts.smc.particles,
            "prior": f"dirichlet({opts.model.alpha:g})",
            "noise": "vonmises, kappa marginalised",
        }
    elif opts.method == "paper":
        by |= {"particles": opts.pf.particles, "likelihood": opts.pf.likelihood}
    table = FusionTable(
        run.names,
        default(slot[0]) or default_weights_for(run.names),
        Network(Path(name).stem.split(".")[0], steps),
        dict(by),
    )
    return table, len(groups), len(groups) - len(live)


def estimate_file(
    src: str | Path,
    *,
    out: str | Path,
    opts: EstimateOptions,
    progress: Callable[[float, float], None] | None = None,
    subgoals: bool = False,
) -> EstimateResult:
    """Read a segmented log, estimate, and write the fusion table to ``out``.

    With ``subgoals`` the demo's decision points (turns the teacher took into an opening the
    learned fusion would pass by) become landmark sub-goal steps (:mod:`lfdfuse.estimate.subgoals`).
    """
    run = read_segmented(src)
    table, n, skipped = estimate_run(run, opts=opts, name=Path(src).name, progress=progress)
    if subgoals:
        from lfdfuse.estimate.subgoals import estimate_with_subgoals, track_of

        table = estimate_with_subgoals(run, track_of(src, run), opts=opts, name=Path(src).name).table
    write_table(table, out)
    return EstimateResult(table, str(out), n, skipped)
