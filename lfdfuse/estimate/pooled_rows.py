"""A leaf's rows pooled over demos, and how much a person's correction weighs in them.

A row another demo adds informative steps to is estimated again on the pooled steps: the
product over the demos (as :mod:`lfdfuse.estimate.pooled_estimate` does), so each demo weighs by
its count of steps in the row. A teacher's demo has many (a row with a thousand demo steps barely
moves for a person's 160 ticks), so in the goal steps the person took over, the weighing of
their ticks is a choice (:data:`WEIGHINGS`):

``pool``
    the product over every demo's steps, as they are (the default);
``even``
    the person's ticks weighed even with the demos': in a row the person drove at least
    ``min_samples`` ticks, the demos' steps thinned evenly (over the demos' steps in order) to
    as many as the person's;
``person``
    the person's ticks alone, in such a row.

Elsewhere, and in a row the person drove fewer ticks than that, every weighing is ``pool``.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from dataclasses import replace
from typing import Literal

import numpy as np

from lfdfuse.estimate.baselines import angle_errors
from lfdfuse.estimate.commands import Commands
from lfdfuse.estimate.demo_alignment import problem_of, row_rng
from lfdfuse.estimate.methods import EstimateOptions, estimate_groups
from lfdfuse.network.table import FusionRow, Step
from lfdfuse.segment.read import SegmentedRun

#: a row of a sub-step pooled over demos draws from ``row_rng(seed, SUBSTEP, leaf, bac)``
SUBSTEP = 2

Weighing = Literal["pool", "even", "person"]
#: how a correction's ticks weigh in the rows of the goal steps the person took over
WEIGHINGS: tuple[Weighing, ...] = ("pool", "even", "person")

Parts = Sequence[tuple[int, np.ndarray]]


def evenly(n_of: int, n: int) -> np.ndarray:
    """``n`` positions of ``0 … n_of − 1`` spread evenly, first and last kept (all if ``n ≥ n_of``)."""
    if n >= n_of:
        return np.arange(n_of)
    if n <= 0:
        return np.zeros(0, dtype=int)
    return np.linspace(0, n_of - 1, n).round().astype(int)


def weighed(
    parts: Parts, *, corrections: Collection[int], weighing: Weighing, min_samples: int
) -> list[tuple[int, np.ndarray]]:
    """One row's ``parts`` (demo, its steps) with the corrections' ticks weighed by ``weighing``
    (see the module docstring): ``pool``, or fewer than ``min_samples`` person ticks, as they are."""
    person = sum(len(t) for e, t in parts if e in corrections)
    if weighing == "pool" or person < min_samples:
        return list(parts)
    if weighing == "person":
        return [(e, t) for e, t in parts if e in corrections]
    demo = [k for k, (e, _) in enumerate(parts) if e not in corrections]
    sizes = [len(parts[k][1]) for k in demo]
    keep = evenly(sum(sizes), person)
    starts = np.cumsum([0, *sizes])
    out: list[tuple[int, np.ndarray]] = []
    for k, (e, t) in enumerate(parts):
        if e in corrections:
            out.append((e, t))
            continue
        i = demo.index(k)
        mine = keep[(keep >= starts[i]) & (keep < starts[i + 1])] - starts[i]
        if len(mine):
            out.append((e, t[mine]))
    return out


def pooled_leaf(
    leaf_no: int,
    base: Step,
    parts: Parts,
    views: Sequence[SegmentedRun],
    models: Sequence[Commands],
    opts: EstimateOptions,
    corrections: Collection[int] = (),
    weighing: Weighing = "pool",
) -> Step:
    """``base`` with every row a further demo (any but the first) adds steps to estimated again
    on the pooled steps of ``parts`` (the corrections' ticks weighed by ``weighing``); its other
    rows as they are. A row the first demo pins (``opts.min_samples`` steps or more) that only
    ``corrections`` add to, fewer steps than that in all, stays as it is: a person's few ticks
    in a row are one manoeuvre somewhere the row drives (the mouth of a dead end, a drive on past
    a goal), and the row drives everywhere its BAC comes up in the step, where the demo's many
    steps showed how."""
    behaviors = views[0].names
    by_bac: dict[int, list[tuple[int, np.ndarray]]] = {}
    for e, ticks in parts:
        bac = views[e].bac[ticks]
        for b in sorted(set(bac.tolist())):
            if b:
                by_bac.setdefault(int(b), []).append((e, ticks[bac == b]))
    rows = {r.bac: r for r in base.fusion}
    bins = models[0].bins
    changed = False
    for b, bparts in sorted(by_bac.items()):
        added = sum(len(t) for e, t in bparts if e != 0)
        if not added:
            continue
        before = rows.get(b)
        if (
            before is not None
            and added < opts.min_samples <= (before.samples or 0)
            and all(e in corrections for e, t in bparts if e != 0 and len(t))
        ):
            continue
        bparts = weighed(bparts, corrections=corrections, weighing=weighing, min_samples=opts.min_samples)
        app = tuple(i for i in range(len(behaviors)) if b >> i & 1)
        p = problem_of(bparts, views, app, models, bins)
        est = estimate_groups([p], opts=opts, rng=row_rng(opts.seed, SUBSTEP, leaf_no, b), bins=bins)[0]
        err = float(np.degrees(angle_errors(p.vectors, p.demo, est.weights).mean()))
        app_names = [behaviors[i] for i in app]
        total = sum(len(t) for _, t in bparts)
        changed = True
        rows[b] = FusionRow(
            bac=b,
            weights={nm: float(x) for nm, x in zip(app_names, est.weights, strict=True)},
            std={nm: float(x) for nm, x in zip(app_names, est.std, strict=True)},
            samples=total,
            fit_error_deg=err if math.isfinite(err) else 180.0,
            low_samples=total < opts.min_samples,
            trial_std=None
            if est.trial_std is None
            else {nm: float(x) for nm, x in zip(app_names, est.trial_std, strict=True)},
            identifiable=est.identifiable,
            samples_added=added,
            weights_before=None if before is None else dict(before.weights),
        )
    if not changed:
        return base
    return replace(base, fusion=tuple(rows[b] for b in sorted(rows)))
