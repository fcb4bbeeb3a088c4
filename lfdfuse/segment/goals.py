"""Goal segments and BAC sub-segments of a demonstration (paper Section IV-A).

A new *goal segment* starts whenever the goal of any behaviour becomes met (rising edge); the
same goal met twice gives two segments. Inside a segment a new *BAC sub-segment* starts whenever
any precondition flips.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from lfdfuse.behaviors.primitives import BehaviorOutputs
from lfdfuse.behaviors.spec import attract_target


@dataclass(frozen=True)
class GoalSegment:
    """Steps ``[start, stop)`` of the demonstration, ended by ``goal`` (None: no goal reached)."""

    index: int
    start: int
    stop: int
    goal: str | None

    @property
    def target(self) -> str | None:
        return attract_target(self.goal) if self.goal else None


@dataclass(frozen=True)
class Segmentation:
    """Goal segments and per-step BACs of a demonstration."""

    segments: tuple[GoalSegment, ...]
    segment_of: np.ndarray  # (N,) segment index of every step
    bac: np.ndarray  # (N,) int64 bit mask

    def bac_runs(self, seg: GoalSegment) -> list[tuple[int, int, int]]:
        """BAC sub-segments ``(bac, start, stop)`` of one goal segment, in time order."""
        b = self.bac[seg.start : seg.stop]
        if len(b) == 0:
            return []
        cuts = np.nonzero(np.diff(b))[0] + 1
        starts = np.concatenate([[0], cuts])
        stops = np.concatenate([cuts, [len(b)]])
        return [
            (int(b[s]), seg.start + int(s), seg.start + int(e)) for s, e in zip(starts, stops, strict=True)
        ]


def segment_goals(
    goal_met: np.ndarray, names: tuple[str, ...], *, refractory_steps: int = 10
) -> list[tuple[int, str]]:
    """Goal achievements ``(step, behaviour)``: rising edges of ``goal_met (N, K)``.

    A goal that flickers (met, unmet for fewer than ``refractory_steps``, met again) is one
    achievement, not two. Achievements at the same step are ordered by behaviour index.
    """
    n, k = goal_met.shape
    events: list[tuple[int, int]] = []
    for j in range(k):
        col = goal_met[:, j]
        prev = np.concatenate([[False], col[:-1]])
        rises = np.nonzero(col & ~prev)[0]
        last_met = -(10**9)
        for s in rises:
            falls_before = np.nonzero(col[:s])[0]
            last_met = int(falls_before[-1]) if len(falls_before) else -(10**9)
            if s - last_met > refractory_steps:
                events.append((int(s), j))
    events.sort()
    return [(s, names[j]) for s, j in events]


def segment_outputs(outputs: BehaviorOutputs, *, refractory_steps: int = 10) -> Segmentation:
    """Goal segments and BACs from behaviour outputs."""
    n = outputs.applicable.shape[0]
    events = segment_goals(outputs.goal_met, outputs.names, refractory_steps=refractory_steps)
    segments: list[GoalSegment] = []
    start = 0
    for step, goal in events:
        if step + 1 <= start:
            continue  # two goals met at the same step: the first one ends the segment
        segments.append(GoalSegment(len(segments), start, step + 1, goal))
        start = step + 1
    if start < n:
        segments.append(GoalSegment(len(segments), start, n, None))
    seg_of = np.zeros(n, dtype=np.int64)
    for s in segments:
        seg_of[s.start : s.stop] = s.index
    return Segmentation(tuple(segments), seg_of, outputs.bac)


def bac_summary(segm: Segmentation, seg: GoalSegment) -> list[tuple[int, int, int]]:
    """``(bac, samples, runs)`` of one goal segment, most samples first."""
    runs = segm.bac_runs(seg)
    samples: Counter[int] = Counter()
    count: Counter[int] = Counter()
    for b, s, e in runs:
        samples[b] += e - s
        count[b] += 1
    return sorted(((b, samples[b], count[b]) for b in samples), key=lambda x: (-x[1], x[0]))
