"""A goal step's rows with its goal in view, learned from the teacher's approach alone.

A teacher steers at a goal only once near it; before that, with the goal already in view far
ahead, they drive on in their style. The paper's rows are per BAC, and the BAC does not change
with the goal's distance: a row with the goal in view learned mostly where the teacher drove on
pulls little toward it, and a robot a little off the teacher's line drives past the goal (the
BAC it is in there may be one the teacher only met far from the goal).

:func:`approach_run` marks the steps of a goal segment with its goal in view before the teacher
began to head at it non-informative, and pools the steps after (the approach) into one BAC, the
union of theirs; :func:`spread` writes that pooled row for every BAC with the goal in view the
teacher met in the segment. The step then heads at its goal whenever it is in view, in the
manner the teacher approached it. A repair (:mod:`lfdfuse.execute.repair`), not the default: it
trades the style's line while the goal is far ahead for reaching it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from lfdfuse.network.table import Step
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.read import SegmentedRun

#: the teacher heads at the goal while the demonstrated vector points at its attractor within this
HOMING_RAD = math.radians(20.0)


@dataclass(frozen=True)
class Approach:
    """One goal segment's approach: its pooled BAC and every BAC with the goal in view met."""

    segment: int
    pooled: int
    in_view: tuple[int, ...]


def homing_begins(run: SegmentedRun, seg: GoalSegment) -> int | None:
    """The step the teacher's approach to the segment's goal began: after the last informative
    step with the goal in view at which they did not head at it (None: the goal never in view)."""
    if seg.goal not in run.names:
        return None
    k = run.names.index(seg.goal)
    lo, hi = seg.start, seg.stop
    seen = run.applicable[lo:hi, k]
    if not (seen & run.informative[lo:hi]).any():
        return None
    goal, demo = run.vectors[lo:hi, k], run.demo[lo:hi]
    off = np.arctan2(demo[:, 1], demo[:, 0]) - np.arctan2(goal[:, 1], goal[:, 0])
    heading_at = np.abs(np.arctan2(np.sin(off), np.cos(off))) < HOMING_RAD
    away = np.nonzero(seen & ~heading_at & run.informative[lo:hi])[0]
    return lo + (int(away[-1]) + 1 if len(away) else 0)


def approach_run(
    run: SegmentedRun, segments: Sequence[GoalSegment]
) -> tuple[SegmentedRun, tuple[Approach, ...]]:
    """``run`` with each segment's goal-in-view steps before its approach non-informative and those
    of the approach one BAC (the union of their BACs; a behaviour not applicable at a step adds
    nothing there). Segments whose teacher never headed at the goal in view are left as they are."""
    bac, informative, vectors = run.bac.copy(), run.informative.copy(), run.vectors.copy()
    out: list[Approach] = []
    for seg in segments:
        begins = homing_begins(run, seg)
        if begins is None:
            continue
        k = run.names.index(str(seg.goal))
        sl = np.arange(seg.start, seg.stop)
        seen = sl[run.applicable[sl, k]]
        homing = seen[(seen >= begins) & run.informative[seen]]
        if not len(homing):
            continue
        pooled = int(np.bitwise_or.reduce(run.bac[homing]))
        in_view = tuple(sorted({int(b) for b in run.bac[seen]}))
        informative[seen[seen < begins]] = False
        bac[seen] = pooled
        vectors[seen] *= run.applicable[seen][:, :, None]
        out.append(Approach(seg.index, pooled, in_view))
    return replace(run, bac=bac, informative=informative, vectors=vectors), tuple(out)


def spread(step: Step, approach: Approach, names: Sequence[str]) -> Step:
    """``step`` (estimated on :func:`approach_run`'s run) with the pooled row written for every BAC
    with the goal in view the teacher met (each with the weights of its own behaviours, and the
    approach's samples: the steps it was learned from)."""
    pooled = step.row(approach.pooled)
    if pooled is None:
        return step
    rows = [r for r in step.fusion if r.bac != approach.pooled]
    for b in approach.in_view:
        mine = {n for i, n in enumerate(names) if b >> i & 1}
        rows.append(
            replace(
                pooled,
                bac=b,
                weights=_only(pooled.weights, mine),
                std=None if pooled.std is None else _only(pooled.std, mine),
                trial_std=None if pooled.trial_std is None else _only(pooled.trial_std, mine),
            )
        )
    return replace(step, fusion=tuple(sorted(rows, key=lambda r: r.bac)))


def _only(values: dict[str, float], names: set[str]) -> dict[str, float]:
    return {n: v for n, v in values.items() if n in names}
