"""Pooling demos: several segmented runs as one estimate's steps and rows.

Each demo keeps its own segmentation (and so its own lag: ``segment`` applied it); pooling only
says which of its goal segments is which network step, and which of its steps a row pools.

* **Goal matching** (:func:`align`): the first demo's goal segments are the network's steps, in
  order; every further demo's segments are matched to them by goal, in order (a demo may cover
  part of the task, or start at a later leg). A goal the steps do not have yet becomes a new step
  where the demo met it. A trailing segment with no goal reached is the step the demo was on its
  way to: the next step after its last matched one (a demo that reached every goal: the steps'
  own goal-free tail, made if absent).
* **Rows** (:func:`pooled_groups`): a row is a (step, BAC); its parts are, per demo that has it,
  the demo's informative steps there. A row's likelihood is the product over its parts: for the
  continuous heading model and for least squares that is one problem of the concatenated steps
  (:func:`problem_of`). Each demo keeps its own command model: a keyboard demo's
  decisions observe the bins of its own command set, and a row pooling a scripted demo with a
  person's keyboard correction reads each by its own model, each with its own noise
  (:class:`~lfdfuse.estimate.model.MixedRowData`) — which is why the parts are carried apart.
* **Random streams** (:func:`row_rng`): every row draws from its own stream keyed by the seed,
  its step and its BAC, so adding a demo that does not touch a row leaves it bit-identical.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lfdfuse.estimate.commands import Commands
from lfdfuse.estimate.methods import Problem
from lfdfuse.estimate.model import CommandBins
from lfdfuse.segment.read import SegmentedRun

#: the key of a row's stream: ``row_rng`` keys are ``(seed, ROW, step, bac)``, a default fit's
#: ``(seed, DEFAULT, step + 1)`` (step 0: the table's)
ROW, DEFAULT = 0, 1


def row_rng(seed: int, *key: int) -> np.random.Generator:
    """The random stream of one row or fit: ``seed`` and its key (see :data:`ROW`)."""
    return np.random.default_rng([seed, *key])


@dataclass(frozen=True)
class Alignment:
    """The pooled network steps' goals, and per demo the step of each of its goal segments."""

    goals: tuple[str | None, ...]  # per step: the goal (a behaviour name, ``attract_*``) or None
    step_of: tuple[tuple[int, ...], ...]  # per demo, per goal segment (in order): its step


def align(runs: Sequence[SegmentedRun]) -> Alignment:
    """Match the demos' goal segments to one step sequence by goal (see the module docstring)."""
    goals: list[str | None] = [s.goal for s in runs[0].segments]
    maps: list[list[int]] = [list(range(len(goals)))]
    for run in runs[1:]:
        # positions are re-read after every insertion: earlier demos' maps shift with it
        mine: list[int] = []
        at = 0  # the first step this segment may match
        for seg in run.segments:
            if seg.goal is None:
                j = at if at < len(goals) else _tail(goals, maps)
            else:
                j = next((i for i in range(at, len(goals)) if goals[i] == seg.goal), -1)
                if j < 0:
                    j = at
                    goals.insert(j, seg.goal)
                    for m in (*maps, mine):
                        m[:] = [i + 1 if i >= j else i for i in m]
            mine.append(j)
            at = j + 1
        maps.append(mine)
    return Alignment(tuple(goals), tuple(tuple(m) for m in maps))


def _tail(goals: list[str | None], maps: list[list[int]]) -> int:
    """The goal-free last step (appended when the steps end on a goal)."""
    if goals and goals[-1] is None:
        return len(goals) - 1
    goals.append(None)
    return len(goals) - 1


@dataclass(frozen=True)
class PooledGroup:
    """The steps of one (network step, BAC) over the demos: ``parts`` per demo that has it."""

    step: int
    bac: int
    behaviors: tuple[int, ...]  # indices of the applicable behaviours
    parts: tuple[tuple[int, np.ndarray], ...]  # (demo, its informative step indices), demo order

    @property
    def samples(self) -> int:
        return sum(len(s) for _, s in self.parts)

    def samples_of(self, demo: int) -> int:
        return sum(len(s) for d, s in self.parts if d == demo)


def pooled_groups(runs: Sequence[SegmentedRun], al: Alignment) -> list[PooledGroup]:
    """Every (step, BAC) any demo met, in step order then BAC order, with its parts.

    A BAC a demo met only on uninformative steps is a part with no steps (the row exists, as for
    one demo).
    """
    k = len(runs[0].names)
    found: dict[tuple[int, int], list[tuple[int, np.ndarray]]] = {}
    for d, run in enumerate(runs):
        for seg, step in zip(run.segments, al.step_of[d], strict=True):
            sl = np.arange(seg.start, seg.stop)
            for b in sorted(set(run.bac[sl].tolist())):
                if not b:
                    continue
                steps = sl[(run.bac[sl] == b) & run.informative[sl]]
                found.setdefault((step, int(b)), []).append((d, steps))
    out = []
    for step, b in sorted(found):
        parts = found[(step, b)]
        merged: dict[int, list[np.ndarray]] = {}
        for d, s in parts:
            merged.setdefault(d, []).append(s)
        app = tuple(i for i in range(k) if b >> i & 1)
        out.append(PooledGroup(step, b, app, tuple((d, np.concatenate(v)) for d, v in merged.items())))
    return out


def problem_of(
    parts: Sequence[tuple[int, np.ndarray]],
    runs: Sequence[SegmentedRun],
    behaviors: Sequence[int],
    models: Sequence[Commands] | None = None,
    bins: CommandBins | None = None,
) -> Problem:
    """One problem of the parts' steps, concatenated in demo order (one demo's part: exactly its
    steps, as a single-demo estimate has them). ``models``: each demo's command model, ``bins``
    the command set the rows are estimated with (the first demo's). Where every part's demo has
    that model, the problem is read by it (with the discrete model's observed intervals);
    otherwise each step keeps its own demo's model (``Problem.commands``)."""
    cols = list(behaviors)
    vec = np.concatenate([runs[d].vectors[s][:, cols, :] for d, s in parts])
    dem = np.concatenate([runs[d].demo[s] for d, s in parts])
    if models is None or (bins is None and all(models[d].bins is None for d, _ in parts)):
        return Problem(vec, dem)
    own = [models[d] for d, _ in parts]
    n = len(dem)
    bounds = np.zeros((n, 2))
    k = 0
    for (_, s), m in zip(parts, own, strict=True):
        if m.bounds is not None:
            bounds[k : k + len(s)] = m.bounds[s]
        k += len(s)
    if all(m.bins == bins for m in own):
        return Problem(vec, dem, bounds)
    sizes = np.concatenate(
        [np.full(len(s), 0 if m.bins is None else m.bins.size) for (_, s), m in zip(parts, own, strict=True)]
    )
    return Problem(vec, dem, bounds, sizes)


def same_behaviors(runs: Sequence[SegmentedRun], names: Sequence[str]) -> str | None:
    """Why the demos cannot be pooled (their behaviour sets differ), or None."""
    first = tuple(runs[0].names)
    for run, name in zip(runs[1:], names[1:], strict=True):
        if tuple(run.names) != first:
            return (
                f"{name} was segmented with other behaviours ({', '.join(run.names)}) than "
                f"{names[0]} ({', '.join(first)}): segment both with the same --behaviors"
            )
    return None
