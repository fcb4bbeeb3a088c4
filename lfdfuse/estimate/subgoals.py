"""Sub-goals at decision points in the fusion table.

:func:`refine` takes the paper's table of a segmented demo (one fusion step per goal segment,
:func:`lfdfuse.estimate.pipeline.estimate_run`) and replays its fusion over the demo
(:func:`fused_vectors`); where the teacher turned off into an opening that fusion would have
driven past, :mod:`lfdfuse.segment.decisions` finds a decision point. Only the sub-segments of
the goal segments with decisions are estimated, and each such goal step becomes a small network::

    reach-green:  to-left-opening-1 (landmark: 1st opening on the left)
                  turn-left-1       (landmark: turned ≥ 68° to the left)
                  reach-green       (goal: green)

Goal steps without a decision keep the first pass's step unchanged, so tasks whose targets lie
on the style's route get the same table as before.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from lfdfuse.errors import LogError
from lfdfuse.estimate.approach import approach_run, spread
from lfdfuse.estimate.methods import EstimateOptions
from lfdfuse.estimate.replay import fused_vectors
from lfdfuse.estimate.segments import estimate_segments, run_rng
from lfdfuse.log.reader import Run
from lfdfuse.network.landmark_goals import Ahead, Landmark, OpeningCount
from lfdfuse.network.table import FusionTable, Network, Step
from lfdfuse.progress import Progress, tell
from lfdfuse.segment.decisions import DecisionParams, DecisionPoint, find_decisions, split_segments
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.read import SegmentedRun
from lfdfuse.segment.track import LandmarkTrack, OpeningCue, landmark_track


def track_of(
    raw: Run,
    run: SegmentedRun,
    *,
    source: str = "the log",
    short_lag_m: float | None = DecisionParams.short_lag_m,
) -> LandmarkTrack:
    """Landmark cues of a segmented run's steps, from the same log's ``/scan`` and ``/pose``
    (odometry); with ``short_lag_m``, also as sectors held that far back see them."""
    if raw.pose is None or len(raw.t_ns) != len(run.t_ns):
        raise LogError(f"{source}: no odometry (/pose) on the scan clock: sub-goals need it")
    return landmark_track(raw.ranges_m, raw.geometry, raw.pose, short_lag_m=short_lag_m)


@dataclass(frozen=True)
class SubgoalResult:
    table: FusionTable
    decisions: tuple[DecisionPoint, ...]


def refine(
    table: FusionTable,
    run: SegmentedRun,
    track: LandmarkTrack,
    *,
    opts: EstimateOptions,
    params: DecisionParams = DecisionParams(),
    progress: Progress | None = None,
    forced: Sequence[int] = (),
    cues: Mapping[int, OpeningCue] | None = None,
    whole: Collection[int] = (),
    rest: Collection[int] = (),
    approach: Collection[int] = (),
    plain: Collection[int] = (),
) -> SubgoalResult:
    """``table`` (the paper's table of ``run``) with sub-goals at the run's decision points.

    Only the sub-segments of goal segments with a decision are estimated; every other step of
    ``table`` is kept as it is. ``forced``, ``cues``, ``whole``: see :func:`find_decisions`;
    ``rest``: goal segments whose step after the last turn keeps the goal step's rows of
    ``table``. ``approach``: goal segments without a decision whose rows with the goal in view
    are learned from the teacher's approach to it (:mod:`lfdfuse.estimate.approach`).
    ``plain``: goal segments whose decisions are dropped: their step stays the paper's (their
    sub-segments are still estimated with the others, so that every other step comes out the same).
    ``progress`` is told how far the sub-segments' pass is.
    """
    decisions = find_decisions(
        segments=run.segments,
        demo=run.demo,
        informative=run.informative,
        fused=fused_vectors(table, run, np.arange(len(run.t_ns))),
        track=track,
        params=params,
        forced=forced,
        cues=cues,
        whole=whole,
    )
    kept = [d for d in decisions if d.segment not in plain]
    if approach:
        table = _approached(
            table, run, opts, [s for s in run.segments if s.index in approach and s.goal], kept
        )
    if not kept:
        tell(progress, 1.0, 1.0)
        return SubgoalResult(table, ())
    subs = split_segments(run.segments, decisions)
    seg_of = np.zeros_like(run.segment_of)
    for _, s in subs:
        seg_of[s.start : s.stop] = s.index
    decided = {d.segment for d in decisions}
    new = [(orig, s) for orig, s in subs if orig in decided]
    sub_run = replace(run, segments=tuple(s for _, s in new), segment_of=seg_of)
    est = estimate_segments(
        sub_run, opts=opts, rng=run_rng(run, opts), table_default=False, progress=progress
    )
    sub_steps = dict(zip((s.index for _, s in new), est.steps, strict=True))
    steps = list(table.network.steps)
    for seg in run.segments:
        mine = [d for d in kept if d.segment == seg.index]
        if not mine:
            continue
        parts = [sub_steps[s.index] for orig, s in new if orig == seg.index]
        inner: list[Step] = []
        for k, d in enumerate(mine):
            tag = f"-{k + 1}" if len(mine) > 1 else ""
            inner += decision_steps(d, parts[2 * k], parts[2 * k + 1], tag)
        old = steps[seg.index]
        # after the last turn: the rows of what followed it, or (``rest``) the goal step's own
        inner.append(old if seg.index in rest else replace(parts[-1], name=old.name))
        steps[seg.index] = Step(old.name, old.goal, (), Network(old.name, tuple(inner)))
    return SubgoalResult(replace(table, network=replace(table.network, steps=tuple(steps))), tuple(kept))


def decision_steps(d: DecisionPoint, drive: Step, turn: Step, tag: str = "") -> list[Step]:
    """The landmark steps of decision ``d``: drive on to its opening with ``drive``'s rows (none
    for a turn from the sub-segment's start), then turn into it with ``turn``'s; ``tag`` tells
    several decisions of one goal step apart."""
    out: list[Step] = []
    if not d.at_start:
        out.append(
            replace(
                drive,
                name=f"to-{d.side}-opening-{d.nth}{tag}",
                goal=None,
                landmark=Landmark(
                    "opening",
                    d.side,
                    d.nth,
                    d.odometry_m,
                    count=OpeningCount.PASSED if d.cue == OpeningCue.PASSED else OpeningCount.ALL,
                    within_m=d.within_m,
                    ahead=None if d.ahead_open is None else (Ahead.OPEN if d.ahead_open else Ahead.CLOSED),
                    lag_m=d.lag_m,
                ),
            )
        )
    out.append(
        replace(
            turn,
            name=f"turn-{d.side}{tag}",
            goal=None,
            landmark=Landmark("turned", d.side, angle_rad=d.angle_rad, lag_m=d.lag_m),
        )
    )
    return out


def _approached(
    table: FusionTable,
    run: SegmentedRun,
    opts: EstimateOptions,
    segments: Sequence[GoalSegment],
    decisions: Sequence[DecisionPoint],
) -> FusionTable:
    """``table`` with the steps of ``segments`` (those without a decision) estimated again with
    their rows with the goal in view learned from the teacher's approach alone."""
    decided = {d.segment for d in decisions}
    mine = [s for s in segments if s.index not in decided]
    if not mine:
        return table
    moved, approaches = approach_run(run, mine)
    if not approaches:
        return table
    redo = [s for s in mine if s.index in {a.segment for a in approaches}]
    est = estimate_segments(
        replace(moved, segments=tuple(redo)), opts=opts, rng=run_rng(run, opts), table_default=False
    )
    steps = list(table.network.steps)
    for a, step in zip(approaches, est.steps, strict=True):
        steps[a.segment] = spread(replace(step, name=steps[a.segment].name), a, run.names)
    return replace(table, network=replace(table.network, steps=tuple(steps)))
