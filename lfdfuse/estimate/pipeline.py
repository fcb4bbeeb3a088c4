"""``estimate``: from a segmented demo to a fusion table (paper Sections IV-B and IV-C).

For every goal segment and every BAC inside it, the informative steps are pooled into a *group*
and the weights of the applicable behaviours are estimated with the chosen method
(:mod:`lfdfuse.estimate.methods`). One network step per goal segment, in order, named after its
goal; a trailing part with no goal reached becomes a step with goal null.

``pf`` samples every group of the run (and the default-weight fits) in one batched tempered SMC
pass (:mod:`lfdfuse.estimate.smc`) — ``--trials K`` included. A group with one applicable
behaviour gets weight 1; a group with no informative step is skipped (its BAC falls back to the
default weights).

Reading the log and refining the table with sub-goals are the caller's (:mod:`lfdfuse.learn`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.baselines import angle_errors
from lfdfuse.estimate.commands import commands_of, decision_steps, observed_bounds
from lfdfuse.estimate.methods import (
    EstimateOptions,
    Method,
    Problem,
    RowEstimate,
    check_options,
    estimate_group,
    estimate_groups,
    provenance,
)
from lfdfuse.estimate.model import CommandBins
from lfdfuse.estimate.pool import (
    DEFAULT,
    ROW,
    Alignment,
    PooledGroup,
    align,
    pooled_groups,
    problem_of,
    row_rng,
    same_behaviors,
)
from lfdfuse.network.table import FusionRow, FusionTable, Network, Step, default_weights_for
from lfdfuse.progress import Progress, part, tell
from lfdfuse.segment.read import SegmentedRun

__all__ = [
    "EstimateOptions",
    "Group",
    "Method",
    "RowEstimate",
    "SegmentSteps",
    "estimate_group",
    "estimate_groups",
    "estimate_pooled",
    "estimate_run",
    "estimate_runs",
    "estimate_segments",
    "groups_of",
    "step_names",
]


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


def step_names(goals: list[str | None]) -> list[str]:
    names: list[str] = []
    for g in goals:
        base = f"reach-{g}" if g else "free"
        name, i = base, 2
        while name in names:
            name, i = f"{base}-{i}", i + 1
        names.append(name)
    return names


def _default_masks(
    run: SegmentedRun, opts: EstimateOptions, *, table_default: bool
) -> tuple[list[int], list[np.ndarray | None]]:
    """The goal-free behaviours, and per default fit (the table's when asked, then each step's)
    its steps or None.

    The default weights meet an unseen situation in the demonstrated manner: the goal-free
    behaviours (all but ``attract_*``) fitted over every informative step of the demo (the
    table's) or of one goal segment (that step's). Too few steps: None (safe wandering for the
    table, the table's default for a step).
    """
    idx = [i for i, n in enumerate(run.names) if not n.startswith("attract_")]
    base = run.informative & run.applicable[:, idx].any(axis=1) if idx else np.zeros_like(run.informative)
    masks: list[np.ndarray | None] = []
    whole: list[np.ndarray | None] = [None] if table_default else []
    for within in [*whole, *(run.segment_of == s.index for s in run.segments)]:
        if within is not None and int((within & run.informative).sum()) < opts.min_samples:
            masks.append(None)
            continue
        mask = base if within is None else base & within
        steps = np.nonzero(mask)[0]
        masks.append(steps if len(idx) and len(steps) >= opts.min_samples else None)
    return idx, masks


@dataclass(frozen=True)
class SegmentSteps:
    """The estimated network steps of a run's goal segments, one per segment in order."""

    steps: tuple[Step, ...]
    default_weights: dict[str, float] | None  # the table's default fit (when asked), None: too few steps
    groups: int
    skipped: int  # groups with no informative step
    commands: str  # the command model the rows were estimated with: continuous | discrete
    bins: CommandBins | None  # its command set (discrete)


def estimate_segments(
    run: SegmentedRun,
    *,
    opts: EstimateOptions,
    rng: np.random.Generator,
    table_default: bool = True,
    progress: Progress | None = None,
) -> SegmentSteps:
    """Estimate every group of ``run.segments`` and each segment's default fit (and the table's,
    with ``table_default``) in one pass of the method. A discrete command model (a person at a
    keyboard) observes each decision once, not each tick it was held (DESIGN §6). ``progress``
    is told how far the pass is, many times over a long one."""
    check_options(opts)
    cm = commands_of(run, requested=opts.commands, recheck_s=opts.model.recheck_s, nudge_s=opts.model.nudge_s)
    if cm.decisions is not None:  # discrete: one observation per decision, not per tick
        run = replace(run, informative=run.informative & cm.decisions)
    bounds = cm.bounds
    groups = groups_of(run)
    live = [g for g in groups if len(g.steps)]
    problems = [
        Problem(
            run.vectors[g.steps][:, list(g.behaviors), :],
            run.demo[g.steps],
            None if bounds is None else bounds[g.steps],
        )
        for g in live
    ]
    idx, masks = _default_masks(run, opts, table_default=table_default)
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
    problems += [
        Problem(run.vectors[s][:, idx, :], run.demo[s], None if bounds is None else bounds[s]) for s in uniq
    ]
    est = estimate_groups(problems, opts=opts, rng=rng, bins=cm.bins, progress=progress)
    rows: dict[int, list[FusionRow]] = {s.index: [] for s in run.segments}
    for g, e, (vec, demo, _) in zip(live, est, problems, strict=False):
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
    first = 1 if table_default else 0
    steps = tuple(
        Step(nm, goal, tuple(rows[s.index]), None, default(slot[first + i]))
        for i, (nm, goal, s) in enumerate(zip(step_names(goals), goals, run.segments, strict=True))
    )
    return SegmentSteps(
        steps,
        default(slot[0]) if table_default else None,
        len(groups),
        len(groups) - len(live),
        cm.mode,
        cm.bins,
    )


def run_rng(run: SegmentedRun, opts: EstimateOptions) -> np.random.Generator:
    """The random stream of :func:`estimate_segments` (sub-goal refinement): the seed and the
    run's length (a demo and its part differ)."""
    return np.random.default_rng([opts.seed, len(run.t_ns)])


def observed(
    run: SegmentedRun, opts: EstimateOptions, bins: CommandBins | None
) -> tuple[SegmentedRun, np.ndarray | None]:
    """``run`` as the rows of a pooled estimate see it: with ``bins`` (a discrete first demo) only
    its decisions are informative, and each step's observed heading interval ``(N, 2)`` in that
    command set comes with it; without, the run as it is (every tick, the continuous model)."""
    if bins is None:
        return run, None
    decided = decision_steps(run, recheck_s=opts.model.recheck_s)
    narrowed = replace(run, informative=run.informative & decided)
    return narrowed, observed_bounds(run, bins, nudge_s=opts.model.nudge_s)


# ------------------------------------------------------------------------------ pooled demos


@dataclass(frozen=True)
class PooledSteps:
    """The network steps of one or more demos (:mod:`lfdfuse.estimate.pool`) and what it took."""

    steps: tuple[Step, ...]
    default_weights: dict[str, float] | None  # the table's default fit, None: too few steps
    groups: int  # (step, BAC) rows any demo met
    skipped: int  # rows with no informative step
    alignment: Alignment
    commands: str  # the first demo's command model (continuous | discrete)
    bins: CommandBins | None  # its command set (discrete), used for the pooled rows too


def _row(
    g: PooledGroup,
    runs: Sequence[SegmentedRun],
    parts: Sequence[tuple[int, np.ndarray]],
    opts: EstimateOptions,
    bins: CommandBins | None,
    bounds: Sequence[np.ndarray] | None,
    progress: Progress | None = None,
) -> tuple[RowEstimate, float]:
    """One row's estimate on ``parts`` (its own random stream) and its mean heading error (°)."""
    p = problem_of(parts, runs, g.behaviors, bounds)
    rng = row_rng(opts.seed, ROW, g.step, g.bac)
    e = estimate_groups([p], opts=opts, rng=rng, bins=bins, progress=progress)[0]
    err = float(np.degrees(angle_errors(p.vectors, p.demo, e.weights).mean()))
    return e, err if math.isfinite(err) else 180.0


def _default_parts(
    runs: Sequence[SegmentedRun], al: Alignment, opts: EstimateOptions
) -> tuple[list[int], list[list[tuple[int, np.ndarray]] | None]]:
    """The goal-free behaviours, and per default fit (the table's, then each step's) its parts or
    None: as :func:`_default_masks`, over the demos pooled (the counts are the pooled ones)."""
    names = runs[0].names
    idx = [i for i, n in enumerate(names) if not n.startswith("attract_")]
    bases = [
        r.informative & r.applicable[:, idx].any(axis=1) if idx else np.zeros_like(r.informative)
        for r in runs
    ]
    out: list[list[tuple[int, np.ndarray]] | None] = []
    for step in (None, *range(len(al.goals))):
        parts: list[tuple[int, np.ndarray]] = []
        seen = 0
        for d, (run, base) in enumerate(zip(runs, bases, strict=True)):
            if step is None:
                within = np.ones(len(run.t_ns), dtype=bool)
            else:
                mine = [s.index for s, j in zip(run.segments, al.step_of[d], strict=True) if j == step]
                within = np.isin(run.segment_of, mine)
                seen += int((within & run.informative).sum())
            steps = np.nonzero(base & within)[0]
            if len(steps):
                parts.append((d, steps))
        total = sum(len(s) for _, s in parts)
        few = step is not None and seen < opts.min_samples
        out.append(parts if idx and not few and total >= opts.min_samples else None)
    return idx, out


def estimate_pooled(
    runs: Sequence[SegmentedRun],
    *,
    opts: EstimateOptions,
    progress: Progress | None = None,
) -> PooledSteps:
    """Estimate the rows of one or more demos pooled (:mod:`lfdfuse.estimate.pool`).

    The first demo is estimated as it would be alone (:func:`estimate_segments`, one pass); a
    row or default fit the other demos add steps to is estimated again on the pooled steps, on its
    own random stream (:func:`~lfdfuse.estimate.pool.row_rng`), and carries ``samples_added`` and
    ``weights_before`` (the first demo's alone). So one demo gives the table it always gave, and
    a row no further demo touched comes out bit-identical to the first demo's.
    """
    check_options(opts)
    al = align(runs)
    # what each demo's rows observe: for a discrete first demo, every demo's decisions and the
    # heading intervals they observe in the first demo's command set (its rows come out so)
    bins = commands_of(
        runs[0], requested=opts.commands, recheck_s=opts.model.recheck_s, nudge_s=opts.model.nudge_s
    ).bins
    seen = [observed(run, opts, bins) for run in runs]
    views = [v for v, _ in seen]
    bounds = None if bins is None else [b for _, b in seen if b is not None]
    groups = pooled_groups(views, al)
    live = [g for g in groups if g.samples]
    idx, dparts = _default_parts(views, al, opts)
    redo = [g for g in live if g.samples != g.samples_of(0)]
    refit = [  # the steps of each default fit estimated again (not the first demo's, not a repeat)
        sum(len(s) for _, s in p)
        if p is not None and any(d for d, _ in p) and not any(_same_parts(q, p) for q in dparts[:j])
        else 0
        for j, p in enumerate(dparts)
    ]
    # progress in steps sampled: the first demo's pass (its rows and default fits: about twice
    # its informative steps), then the rows and default fits the other demos add steps to
    first = 2.0 * float(views[0].informative.sum())
    total = first + float(sum(g.samples for g in redo) + sum(refit))
    base = estimate_segments(
        runs[0],
        opts=opts,
        rng=run_rng(runs[0], opts),
        progress=part(progress, start=0.0, size=first, total=total),
    )
    # the first demo's rows and per-step defaults by pooled step
    own: dict[tuple[int, int], FusionRow] = {}
    own_default: dict[int, dict[str, float] | None] = {}
    for st, j in zip(base.steps, al.step_of[0], strict=True):
        own_default[j] = st.default_weights
        for r in st.fusion:
            own[(j, r.bac)] = r
    done = first
    names = runs[0].names
    rows: dict[int, list[FusionRow]] = {i: [] for i in range(len(al.goals))}
    for g in live:
        if g.samples == g.samples_of(0):
            rows[g.step].append(own[(g.step, g.bac)])
            continue
        sub = part(progress, start=done, size=float(g.samples), total=total)
        e, err = _row(g, views, [p for p in g.parts if len(p[1])], opts, base.bins, bounds, sub)
        app = [names[i] for i in g.behaviors]
        before = own.get((g.step, g.bac))
        rows[g.step].append(
            FusionRow(
                bac=g.bac,
                weights={nm: float(x) for nm, x in zip(app, e.weights, strict=True)},
                std={nm: float(x) for nm, x in zip(app, e.std, strict=True)},
                samples=g.samples,
                fit_error_deg=err,
                low_samples=g.samples < opts.min_samples,
                trial_std=None
                if e.trial_std is None
                else {nm: float(x) for nm, x in zip(app, e.trial_std, strict=True)},
                identifiable=e.identifiable,
                samples_added=g.samples - g.samples_of(0),
                weights_before=None if before is None else dict(before.weights),
            )
        )
        done += g.samples
    fits: list[dict[str, float] | None] = []
    for j, parts in enumerate(dparts):
        if parts is None:
            fits.append(None)
            continue
        if all(d == 0 for d, _ in parts):  # the first demo's own fit (the table's, or its step's)
            fits.append(base.default_weights if j == 0 else own_default.get(j - 1))
            continue
        same = next((i for i in range(j) if _same_parts(dparts[i], parts)), None)
        if same is not None:
            fits.append(fits[same])
            continue
        prob = problem_of(parts, views, idx, bounds)
        sub = part(progress, start=done, size=float(refit[j]), total=total)
        e = estimate_groups(
            [prob], opts=opts, rng=row_rng(opts.seed, DEFAULT, j), bins=base.bins, progress=sub
        )[0]
        done += refit[j]
        fit = {names[i]: round(float(x), 4) for i, x in zip(idx, e.weights, strict=True) if x >= 1e-4}
        fits.append(fit or None)
    tell(progress, total, total)
    goals = [g[len("attract_") :] if g and g.startswith("attract_") else None for g in al.goals]
    steps = tuple(
        Step(nm, goal, tuple(rows[i]), None, fits[1 + i])
        for i, (nm, goal) in enumerate(zip(step_names(goals), goals, strict=True))
    )
    return PooledSteps(steps, fits[0], len(groups), len(groups) - len(live), al, base.commands, base.bins)


def _same_parts(a: list[tuple[int, np.ndarray]] | None, b: list[tuple[int, np.ndarray]] | None) -> bool:
    if a is None or b is None or len(a) != len(b):
        return False
    return all(da == db and np.array_equal(sa, sb) for (da, sa), (db, sb) in zip(a, b, strict=True))


def estimate_runs(
    runs: Sequence[SegmentedRun],
    *,
    opts: EstimateOptions,
    names: Sequence[str],
    progress: Progress | None = None,
) -> tuple[FusionTable, int, int]:
    """The fusion table of one or more segmented runs pooled (named ``names``, the first names the
    network); returns it with the row and skipped counts. Several demos must share their
    behaviour set; the provenance lists them (``sources``)."""
    if not runs or len(runs) != len(names):
        raise ConfigError("estimate needs at least one demonstration")
    why = same_behaviors(runs, names)
    if why is not None:
        raise ConfigError(why)
    # a demo without one informative step (no key pressed, only stops and reversing) has nothing
    # to learn from: an error, not a table of default weights that looks like a result
    if not any(len(g.steps) for run in runs for g in groups_of(run)):
        steps = sum(len(run.t_ns) for run in runs)
        raise ConfigError(
            f"{names[0]}: nothing to learn: none of its {steps} steps carries a heading with a"
            " behaviour applicable (standing still and reversing carry no heading); drive the robot"
            " forward or turning while teaching"
        )
    est = estimate_pooled(runs, opts=opts, progress=progress)
    by = provenance(
        opts,
        source=names[0],
        commands=est.commands,
        lag_s=runs[0].metadata.get("segment_lag_s"),
        bins=est.bins,
    )
    if len(runs) > 1:
        by["sources"] = list(names)
    table = FusionTable(
        runs[0].names,
        est.default_weights or default_weights_for(runs[0].names),
        Network(Path(names[0]).stem.split(".")[0], est.steps),
        by,
    )
    return table, est.groups, est.skipped


def estimate_run(
    run: SegmentedRun,
    *,
    opts: EstimateOptions,
    name: str = "demo",
    progress: Progress | None = None,
) -> tuple[FusionTable, int, int]:
    """The fusion table of a segmented run; returns it with the group and skipped counts."""
    return estimate_runs([run], opts=opts, names=[name], progress=progress)
