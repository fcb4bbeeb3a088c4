"""One segmented demo's rows: every (goal segment, BAC) group estimated in one pass.

For every goal segment and every BAC inside it, the informative steps are pooled into a *group*
and the weights of the applicable behaviours are estimated with the chosen method
(:mod:`lfdfuse.estimate.methods`): one network step per goal segment, in order, named after its
goal (a trailing part with no goal reached becomes a step with goal null). ``pf`` samples every group of the run (and the default-weight fits) in one batched
tempered SMC pass (:mod:`lfdfuse.estimate.smc`) — ``--trials K`` included. A group with one
applicable behaviour gets weight 1; a group with no informative step is skipped (its BAC falls
back to the default weights). Several demos pooled: :mod:`lfdfuse.estimate.pooled_estimate`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import partial

import numpy as np

from lfdfuse.behaviors.spec import attract_target
from lfdfuse.estimate.baselines import angle_errors
from lfdfuse.estimate.commands import commands_of
from lfdfuse.estimate.hierarchy import Hierarchy, centre_of, hierarchical_rows
from lfdfuse.estimate.methods import (
    EstimateOptions,
    Method,
    Problem,
    RowEstimate,
    check_options,
    estimate_groups,
)
from lfdfuse.estimate.model import CommandBins, make_row, row_loglik
from lfdfuse.estimate.person import PersonChoice, choose_person_model
from lfdfuse.network.table import FusionRow, Step
from lfdfuse.progress import Progress
from lfdfuse.segment.read import SegmentedRun


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
    idx = [i for i, n in enumerate(run.names) if attract_target(n) is None]
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
    hierarchy: Hierarchy | None = None  # the rows' prior learned from their steps (discrete, pf)
    person: PersonChoice | None = None  # the command model the demo chose (``select_model``)


def estimate_segments(
    run: SegmentedRun,
    *,
    opts: EstimateOptions,
    rng: np.random.Generator,
    table_default: bool = True,
    progress: Progress | None = None,
    command_set: CommandBins | None = None,
) -> SegmentSteps:
    """Estimate every group of ``run.segments`` and each segment's default fit (and the table's,
    with ``table_default``) in one pass of the method. A discrete command model (a person at a
    keyboard) observes each decision once, not each tick it was held (DESIGN §6). ``progress``
    is told how far the pass is, many times over a long one. ``command_set``: the discrete
    model's command set, when not the run's own (:func:`~lfdfuse.estimate.commands.commands_of`)."""
    check_options(opts)
    chosen = None
    if opts.select_model and opts.commands == "auto" and opts.method == Method.PF:
        chosen = choose_person_model(run, opts, fit_steps)
        if chosen is not None:
            opts = replace(opts, commands=chosen.mode, model=replace(opts.model, lapse=chosen.lapse))
    cm = commands_of(
        run,
        requested=opts.commands,
        recheck_s=opts.model.recheck_s,
        nudge_s=opts.model.nudge_s,
        command_set=command_set,
    )
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
    spread: Hierarchy | None = None
    if opts.model.hierarchy and cm.mode == "discrete" and opts.method == Method.PF and live:
        est, spread = _borrow_from_steps(run, live, est, problems, opts, rng, cm.bins, bounds)
    rows: dict[int, list[FusionRow]] = {s.index: [] for s in run.segments}
    for g, e, (vec, demo, *_) in zip(live, est, problems, strict=False):
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

    goals = [attract_target(s.goal) if s.goal else None for s in run.segments]
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
        spread,
        chosen,
    )


def _borrow_from_steps(
    run: SegmentedRun,
    live: list[Group],
    est: list[RowEstimate],
    row_problems: list[Problem],
    opts: EstimateOptions,
    rng: np.random.Generator,
    bins: CommandBins | None,
    bounds: np.ndarray | None,
) -> tuple[list[RowEstimate], Hierarchy]:
    """The rows' estimates under the hierarchical prior (:mod:`lfdfuse.estimate.hierarchy`):
    each goal segment's weights fitted on all its decisions (a behaviour's vector only where it
    applies), the prior's strength chosen over the rows, the rows reweighted. ``est`` holds the
    rows' flat estimates first (then the default fits, returned unchanged)."""
    k = len(run.names)
    segs = sorted({g.segment for g in live})
    problems = []
    members = []
    for s in segs:
        steps = np.nonzero((run.segment_of == s) & run.informative & run.applicable.any(axis=1))[0]
        beh = [i for i in range(k) if run.applicable[steps, i].any()]
        vec = run.vectors[steps][:, beh, :] * run.applicable[steps][:, beh, None]
        problems.append(Problem(vec, run.demo[steps], None if bounds is None else bounds[steps]))
        members.append(beh)
    fits = estimate_groups(problems, opts=replace(opts, trials=1), rng=rng, bins=bins)
    step_w = {}
    for s, beh, f in zip(segs, members, fits, strict=True):
        w = np.zeros(k)
        w[beh] = f.weights
        step_w[s] = w
    centres = [centre_of(step_w[g.segment], g.behaviors) for g in live]
    draw = np.random.default_rng([opts.seed, len(run.t_ns), 1])
    logliks = [
        partial(row_loglik, make_row(p.vectors, p.demo, bins, p.bounds), model=opts.model)
        for p in row_problems
    ]
    out, h = hierarchical_rows(est[: len(live)], centres, logliks[: len(live)], opts.model.alpha, draw)
    return out + list(est[len(live) :]), h


def fit_steps(run: SegmentedRun, opts: EstimateOptions) -> tuple[Step, ...]:
    """The network steps of ``run`` alone (no table default): a candidate person model's fit."""
    return estimate_segments(run, opts=opts, rng=run_rng(run, opts), table_default=False).steps


def run_rng(run: SegmentedRun, opts: EstimateOptions) -> np.random.Generator:
    """The random stream of :func:`estimate_segments` (sub-goal refinement): the seed and the
    run's length (a demo and its part differ)."""
    return np.random.default_rng([opts.seed, len(run.t_ns)])
