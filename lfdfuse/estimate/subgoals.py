"""Sub-goals at decision points in the fusion table (issue 15).

Two passes over a segmented demo. The first is the paper's: one fusion step per goal segment.
Its fusion is then replayed over the demo (:func:`fused_vectors`); where the teacher turned
off into an opening that fusion would have driven past, :mod:`lfdfuse.segment.decisions`
finds a decision point. The second pass estimates the sub-segments on their own, and each goal
step with decisions becomes a small network::

    reach-green:  to-left-opening-1 (landmark: 1st opening on the left)
                  turn-left-1       (landmark: turned ≥ 68° to the left)
                  reach-green       (goal: green)

Goal steps without a decision keep the first pass's step unchanged, so tasks whose targets lie
on the style's route get the same table as before.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from lfdfuse.errors import LogError
from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.estimate.replay import fused_vectors
from lfdfuse.log.reader import read_run
from lfdfuse.network.landmarks import Landmark
from lfdfuse.network.table import FusionTable, Network, Step
from lfdfuse.segment.decisions import (
    DecisionParams,
    DecisionPoint,
    LandmarkTrack,
    find_decisions,
    landmark_track,
    split_segments,
)
from lfdfuse.segment.read import SegmentedRun


def track_of(path: str | Path, run: SegmentedRun) -> LandmarkTrack:
    """Landmark cues of a segmented log's steps, from its ``/scan`` and ``/pose`` (odometry)."""
    raw = read_run(path)
    if raw.pose is None or len(raw.t_ns) != len(run.t_ns):
        raise LogError(f"{path}: no odometry (/pose) on the scan clock: sub-goals need it")
    return landmark_track(raw.ranges_m, raw.geometry, raw.pose)


@dataclass(frozen=True)
class SubgoalResult:
    table: FusionTable
    decisions: tuple[DecisionPoint, ...]


def estimate_with_subgoals(
    run: SegmentedRun,
    track: LandmarkTrack,
    *,
    opts: EstimateOptions,
    name: str = "demo",
    params: DecisionParams = DecisionParams(),
) -> SubgoalResult:
    """The fusion table of ``run`` with sub-goals at its decision points."""
    table, _, _ = estimate_run(run, opts=opts, name=name)
    decisions = find_decisions(
        segments=run.segments,
        demo=run.demo,
        informative=run.informative,
        fused=fused_vectors(table, run, np.arange(len(run.t_ns))),
        track=track,
        params=params,
    )
    if not decisions:
        return SubgoalResult(table, ())
    subs = split_segments(run.segments, decisions)
    seg_of = np.zeros_like(run.segment_of)
    for _, s in subs:
        seg_of[s.start : s.stop] = s.index
    sub_run = replace(run, segments=tuple(s for _, s in subs), segment_of=seg_of)
    sub_table, _, _ = estimate_run(sub_run, opts=opts, name=name)
    steps = list(table.network.steps)
    for seg in run.segments:
        mine = [d for d in decisions if d.segment == seg.index]
        if not mine:
            continue
        parts = [sub_table.network.steps[s.index] for orig, s in subs if orig == seg.index]
        inner: list[Step] = []
        for k, d in enumerate(mine):
            drive, turn = parts[2 * k], parts[2 * k + 1]
            tag = f"-{k + 1}" if len(mine) > 1 else ""
            if not d.at_start:
                inner.append(
                    replace(
                        drive,
                        name=f"to-{d.side}-opening-{d.nth}{tag}",
                        goal=None,
                        landmark=Landmark("opening", d.side, d.nth, d.odometry_m),
                    )
                )
            inner.append(
                replace(
                    turn,
                    name=f"turn-{d.side}{tag}",
                    goal=None,
                    landmark=Landmark("turned", d.side, angle_rad=d.angle_rad),
                )
            )
        old = steps[seg.index]
        inner.append(replace(parts[-1], name=old.name))
        steps[seg.index] = Step(old.name, old.goal, (), Network(old.name, tuple(inner)))
    return SubgoalResult(replace(table, network=replace(table.network, steps=tuple(steps))), tuple(decisions))
