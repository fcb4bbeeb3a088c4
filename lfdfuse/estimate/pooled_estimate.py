"""Several demos pooled into one set of rows: the first demo's pass, then every row
and default fit the other demos add steps to, estimated again on the pooled steps.

Which steps pool where — demos aligned by their goals, (step, BAC) groups across them, each
demo's command model — is :mod:`lfdfuse.estimate.demo_alignment`; one demo's pass is
:mod:`lfdfuse.estimate.segments`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from lfdfuse.behaviors.spec import attract_target
from lfdfuse.estimate.baselines import angle_errors
from lfdfuse.estimate.commands import Commands, commands_of
from lfdfuse.estimate.demo_alignment import (
    DEFAULT,
    ROW,
    Alignment,
    PooledGroup,
    align,
    pooled_groups,
    problem_of,
    row_rng,
)
from lfdfuse.estimate.hierarchy import Hierarchy
from lfdfuse.estimate.methods import EstimateOptions, Method, RowEstimate, check_options, estimate_groups
from lfdfuse.estimate.model import CommandBins
from lfdfuse.estimate.person import PersonChoice, choose_person_model
from lfdfuse.estimate.segments import estimate_segments, fit_steps, run_rng, step_names
from lfdfuse.network.table import FusionRow, Step
from lfdfuse.progress import Progress, part, tell
from lfdfuse.segment.read import SegmentedRun


@dataclass(frozen=True)
class PooledSteps:
    """The network steps of one or more demos (:mod:`lfdfuse.estimate.demo_alignment`) and what it took."""

    steps: tuple[Step, ...]
    default_weights: dict[str, float] | None  # the table's default fit, None: too few steps
    groups: int  # (step, BAC) rows any demo met
    skipped: int  # rows with no informative step
    alignment: Alignment
    commands: str  # the first demo's command model (continuous | discrete)
    bins: CommandBins | None  # its command set (discrete); every demo's rows observe their own
    source_commands: tuple[str, ...]  # every demo's command model, in order
    hierarchy: Hierarchy | None = None  # the first demo's rows' prior, learned from its steps
    person: PersonChoice | None = None  # the first demo's command model chosen by its data


def _row(
    g: PooledGroup,
    runs: Sequence[SegmentedRun],
    parts: Sequence[tuple[int, np.ndarray]],
    opts: EstimateOptions,
    bins: CommandBins | None,
    models: Sequence[Commands],
    progress: Progress | None = None,
) -> tuple[RowEstimate, float]:
    """One row's estimate on ``parts`` (its own random stream) and its mean heading error (°)."""
    p = problem_of(parts, runs, g.behaviors, models, bins)
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
    idx = [i for i, n in enumerate(names) if attract_target(n) is None]
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
    command_set: CommandBins | None = None,
) -> PooledSteps:
    """Estimate the rows of one or more demos pooled (:mod:`lfdfuse.estimate.demo_alignment`).

    The first demo is estimated as it would be alone (:func:`estimate_segments`, one pass); a
    row or default fit the other demos add steps to is estimated again on the pooled steps, on its
    own random stream (:func:`~lfdfuse.estimate.demo_alignment.row_rng`), and carries ``samples_added`` and
    ``weights_before`` (the first demo's alone). So one demo gives the table it always gave, and
    a row no further demo touched comes out bit-identical to the first demo's. ``command_set``:
    the discrete model's command set, when not the first demo's own.
    """
    check_options(opts)
    chosen = None
    if opts.select_model and opts.commands == "auto" and opts.method == Method.PF:
        # the first demo chooses its person model, and every demo's rows are read by it
        chosen = choose_person_model(runs[0], opts, fit_steps)
    opts = replace(opts, select_model=False)
    if chosen is not None:
        opts = replace(opts, commands=chosen.mode, model=replace(opts.model, lapse=chosen.lapse))
    al = align(runs)
    # each demo keeps its command model: a discrete demo's rows see its decisions only, each
    # observing the heading interval of its own command set (``command_set``: the first demo's)
    models = [
        commands_of(
            run,
            requested=opts.commands,
            recheck_s=opts.model.recheck_s,
            nudge_s=opts.model.nudge_s,
            command_set=command_set if d == 0 else None,
        )
        for d, run in enumerate(runs)
    ]
    views = [
        run if m.decisions is None else replace(run, informative=run.informative & m.decisions)
        for run, m in zip(runs, models, strict=True)
    ]
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
        command_set=command_set,
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
        e, err = _row(g, views, [p for p in g.parts if len(p[1])], opts, base.bins, models, sub)
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
        prob = problem_of(parts, views, idx, models, base.bins)
        sub = part(progress, start=done, size=float(refit[j]), total=total)
        e = estimate_groups(
            [prob], opts=opts, rng=row_rng(opts.seed, DEFAULT, j), bins=base.bins, progress=sub
        )[0]
        done += refit[j]
        fit = {names[i]: round(float(x), 4) for i, x in zip(idx, e.weights, strict=True) if x >= 1e-4}
        fits.append(fit or None)
    tell(progress, total, total)
    goals = [attract_target(g) if g else None for g in al.goals]
    steps = tuple(
        Step(nm, goal, tuple(rows[i]), None, fits[1 + i])
        for i, (nm, goal) in enumerate(zip(step_names(goals), goals, strict=True))
    )
    modes = tuple(m.mode for m in models)
    return PooledSteps(
        steps,
        fits[0],
        len(groups),
        len(groups) - len(live),
        al,
        base.commands,
        base.bins,
        modes,
        base.hierarchy,
        chosen,
    )


def _same_parts(a: list[tuple[int, np.ndarray]] | None, b: list[tuple[int, np.ndarray]] | None) -> bool:
    if a is None or b is None or len(a) != len(b):
        return False
    return all(da == db and np.array_equal(sa, sb) for (da, sa), (db, sb) in zip(a, b, strict=True))
