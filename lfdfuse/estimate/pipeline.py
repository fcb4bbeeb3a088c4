"""``estimate``: from a segmented demo to a fusion table (paper Sections IV-B and IV-C).

For every goal segment and every BAC inside it, the informative steps are pooled and the
weights of the applicable behaviours are estimated with the chosen method. One network step per
goal segment, in order, named after its goal; a trailing part with no goal reached becomes a
step with goal null.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Literal

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.baselines import angle_errors, arbitration_weights, nnls_weights
from lfdfuse.estimate.pf import PFParams, normalise, run_filter
from lfdfuse.network.table import FusionRow, FusionTable, Network, Step, default_weights_for, write_table
from lfdfuse.segment.pipeline import SegmentedRun, read_segmented

Method = Literal["pf", "nnls", "arbitration"]
METHODS: tuple[str, ...] = ("pf", "nnls", "arbitration")


@dataclass(frozen=True)
class EstimateOptions:
    method: Method = "pf"
    trials: int = 1
    seed: int = 0
    pf: PFParams = field(default_factory=PFParams)
    min_samples: int = 30  # rows with fewer informative steps are flagged low_samples


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


def estimate_group(
    vectors: np.ndarray, demo: np.ndarray, *, opts: EstimateOptions, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Normalised weights ``(n,)`` and their std ``(n,)`` for one group: ``vectors (T, n, 2)``."""
    t, n, _ = vectors.shape
    if n == 1:
        return np.ones(1), np.zeros(1)
    k = max(1, opts.trials)
    if opts.method == "pf":
        res = run_filter(vectors, demo, trials=k, rng=rng, params=opts.pf)
        w = res.weights.mean(axis=0)
        std = res.weights.std(axis=0) if k > 1 else res.spread[0]
        return normalise(w), std
    fit: Callable[[np.ndarray, np.ndarray], np.ndarray] = (
        nnls_weights if opts.method == "nnls" else arbitration_weights
    )
    if k == 1:
        return normalise(fit(vectors, demo)), np.zeros(n)
    boots = np.array(
        [normalise(fit(vectors[idx], demo[idx])) for idx in (rng.integers(0, t, t) for _ in range(k))]
    )
    return normalise(boots.mean(axis=0)), boots.std(axis=0)


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
    if opts.trials < 1 or opts.pf.particles < 1:
        raise ConfigError("--trials and --particles must be at least 1")
    groups = groups_of(run)
    rows: dict[int, list[FusionRow]] = {s.index: [] for s in run.segments}
    skipped = 0
    total = float(sum(len(g.steps) for g in groups)) or 1.0
    done = 0.0
    for g in groups:
        if len(g.steps) == 0:
            skipped += 1
            continue
        idx = list(g.behaviors)
        vec = run.vectors[g.steps][:, idx, :]
        demo = run.demo[g.steps]
        rng = np.random.default_rng([opts.seed, g.segment, g.bac])
        w, std = estimate_group(vec, demo, opts=opts, rng=rng)
        err = float(np.degrees(angle_errors(vec, demo, w).mean()))
        names = [run.names[i] for i in idx]
        rows[g.segment].append(
            FusionRow(
                bac=g.bac,
                weights={nm: float(x) for nm, x in zip(names, w, strict=True)},
                std={nm: float(x) for nm, x in zip(names, std, strict=True)},
                samples=int(len(g.steps)),
                fit_error_deg=err if math.isfinite(err) else 180.0,
                low_samples=len(g.steps) < opts.min_samples,
            )
        )
        done += len(g.steps)
        if progress is not None:
            progress(done, total)
    goals = [
        s.goal[len("attract_") :] if s.goal and s.goal.startswith("attract_") else None for s in run.segments
    ]
    steps = tuple(
        Step(nm, goal, tuple(rows[s.index]), None, step_default_weights(run, opts, s.index))
        for nm, goal, s in zip(step_names(goals), goals, run.segments, strict=True)
    )
    est = {
        "method": opts.method,
        "trials": opts.trials,
        "seed": opts.seed,
        "source": name,
    }
    if opts.method == "pf":
        est |= {"particles": opts.pf.particles, "likelihood": opts.pf.likelihood}
    table = FusionTable(
        run.names, default_weights_of(run, opts), Network(Path(name).stem.split(".")[0], steps), est
    )
    return table, len(groups), skipped


def default_weights_of(
    run: SegmentedRun, opts: EstimateOptions, *, within: np.ndarray | None = None, salt: int = 1 << 20
) -> dict[str, float]:
    """Weights for BACs never seen in training: the teacher's overall style.

    The goal-free behaviours (all but ``attract_*``) are fitted over every informative step of
    the demonstration at once, so an unseen situation is met in the demonstrated manner rather
    than by a fixed fallback; when that fit is empty, safe wandering (avoid + wander).
    """
    idx = [i for i, n in enumerate(run.names) if not n.startswith("attract_")]
    mask = run.informative & run.applicable[:, idx].any(axis=1)
    if within is not None:
        mask &= within
    steps = np.nonzero(mask)[0]
    fallback = default_weights_for(run.names)
    if len(idx) == 0 or len(steps) < opts.min_samples:
        return fallback
    rng = np.random.default_rng([opts.seed, salt])
    w, _ = estimate_group(
        run.vectors[steps][:, idx, :], run.demo[steps], opts=replace(opts, trials=1), rng=rng
    )
    out = {run.names[i]: round(float(x), 4) for i, x in zip(idx, w, strict=True) if x >= 1e-4}
    return out or fallback


def estimate_file(
    src: str | Path,
    *,
    out: str | Path,
    opts: EstimateOptions,
    progress: Callable[[float, float], None] | None = None,
) -> EstimateResult:
    """Read a segmented log, estimate, and write the fusion table to ``out``."""
    run = read_segmented(src)
    table, n, skipped = estimate_run(run, opts=opts, name=Path(src).name, progress=progress)
    write_table(table, out)
    return EstimateResult(table, str(out), n, skipped)


def step_default_weights(run: SegmentedRun, opts: EstimateOptions, segment: int) -> dict[str, float] | None:
    """The manner of one step for its unseen BACs: its goal-free behaviours fitted over all of
    its informative steps (None when it has too few)."""
    within = run.segment_of == segment
    if int((within & run.informative).sum()) < opts.min_samples:
        return None
    return default_weights_of(run, opts, within=within, salt=(1 << 20) + 1 + segment)
