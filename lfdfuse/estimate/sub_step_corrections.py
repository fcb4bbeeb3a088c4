"""A correction learned inside the sub-step its network was in (``estimate --subgoals``).

A correction log (``teleop --table``) records the network's active step every tick
(``/lfd/step``, kept by ``segment``). In a goal step that already has sub-goals, the person's
ticks then go to the sub-step the network was in (:func:`labelled_parts`), and a turn-off of the
person's that none of the step's decisions names becomes a decision of that sub-step
(:func:`inside_decision`), its landmark counted from where the network entered it, inserted
before it (:func:`unique_steps`). :func:`goals_of_network` aligns a correction by the goals its network
met, not every target its robot passed (:func:`goals_once`, for a log that kept no steps: a goal
met again while lingering at it). The pooling itself: :mod:`lfdfuse.estimate.pooled_subgoals`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from lfdfuse.estimate.replay import fused_vectors
from lfdfuse.estimate.subgoals import decision_steps
from lfdfuse.network.table import FusionTable, Step
from lfdfuse.segment.decisions import DecisionParams, DecisionPoint, find_decisions
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.read import SegmentedRun
from lfdfuse.segment.track import LandmarkTrack

#: a correction's opening has the shape of the way ahead at its onset or this many steps (half a
#: second) before (:attr:`DecisionParams.shape_steps`): the person, taking over a moment before
#: the place the robot missed, steers for the opening at once and cuts across its mouth, seeing
#: its far wall at the onset, where the robot driving on along the corridor sees the way go on.
#: A longer window also reads corners the person cut as side openings (a decision added where
#: the rows alone would do)
CORRECTION_SHAPE_STEPS = 5

#: a goal met at tick ``m`` is the network's when its step within this many ticks before was that
#: goal's (the network sees the goal met at ``m`` and is on to the next step there)
NETWORK_GOAL_TICKS = 3


@dataclass(frozen=True)
class FurtherDemo:
    """A demo after the first: its segmented run, its landmark track, and whether it is a
    person's correction of a network (its network's ticks non-informative)."""

    name: str
    run: SegmentedRun
    track: LandmarkTrack
    correction: bool
    #: a correction: the network's active step at each of its ticks (``/lfd/step``, nested names
    #: joined by ``/``), where the log kept it; None: not known
    steps: tuple[str | None, ...] | None = None
    #: a correction: whether the person drove at each of its ticks (``/lfd/authority``), where the
    #: log kept it; None: not known (then the person took over once, at the first informative tick)
    person: np.ndarray | None = field(default=None, compare=False)


def taken_over(others: Sequence[FurtherDemo]) -> set[str]:
    """The goal steps (top-level names) the corrections' persons took over in: the network's step
    at the first informative tick of each takeover (a person who watched on after handing back
    may take over again)."""
    out: set[str] = set()
    for o in others:
        if not o.correction or o.steps is None:
            continue
        ticks = np.nonzero(o.run.informative)[0]
        firsts = ticks[:1]
        if o.person is not None and len(o.person) == len(o.run.informative):
            began = np.nonzero(o.person & ~np.concatenate([[False], o.person[:-1]]))[0]
            at_or_after = np.searchsorted(ticks, began)
            firsts = ticks[at_or_after[at_or_after < len(ticks)]]
        for i in firsts.tolist():
            at = o.steps[i]
            if at is not None:
                out.add(at.split("/", 1)[0])
    return out


def goals_once(run: SegmentedRun) -> SegmentedRun:
    """A correction's run with each goal met once: a goal met again right after it was met (the
    robot lingering at it, its network already after the next goal) starts no goal segment; its
    steps belong to the segment after (None: the run ended there)."""
    last: list[str | None] = [None]  # the last goal met

    def first_time(seg: GoalSegment) -> bool:
        again, last[0] = seg.goal == last[0], seg.goal
        return not again

    return _goals_kept(run, first_time)


def goals_of_network(
    run: SegmentedRun, steps: Sequence[str | None], goals: Mapping[str, str]
) -> SegmentedRun:
    """A correction's run with only the goals its network met: a target the robot met while its
    network was after another goal (``steps``: the network's step per tick; ``goals``: each goal
    step's goal, by top-level name) starts no goal segment; its steps belong to the segment after
    (None: the run ended there). The network drives before the person takes over and after the
    hand-back, and may pass a target it is not after, or come round to one it met before."""

    def networks(seg: GoalSegment) -> bool:
        met = seg.stop - 1  # the network sees its goal met at this tick and is on to the next
        after = {steps[i] for i in range(max(met - NETWORK_GOAL_TICKS, 0), met + 1)}
        return any(s is not None and goals.get(s.split("/", 1)[0]) == seg.goal for s in after)

    return _goals_kept(run, networks)


def _goals_kept(run: SegmentedRun, keep: Callable[[GoalSegment], bool]) -> SegmentedRun:
    """``run`` with the goal segments ``keep`` refuses merged into the segment after (None: the
    run ended there)."""
    segs: list[GoalSegment] = []
    start = 0
    for seg in run.segments:
        if seg.goal is not None and not keep(seg):
            continue  # not a goal of this run: on into the next segment
        segs.append(GoalSegment(len(segs), start, seg.stop, seg.goal))
        start = seg.stop
    if start < len(run.t_ns):
        segs.append(GoalSegment(len(segs), start, len(run.t_ns), None))
    if tuple(segs) == run.segments:
        return run
    seg_of = np.empty_like(run.segment_of)
    for g in segs:
        seg_of[g.start : g.stop] = g.index
    return replace(run, segments=tuple(segs), segment_of=seg_of)


@dataclass(frozen=True)
class Inserted:
    """A correction's decision inside one sub-step of a goal step with sub-goals: ``decision``
    counted from where the network entered sub-step ``leaf`` (its name in the goal step's
    network) in correction ``demo``."""

    leaf: str
    decision: DecisionPoint
    demo: int


def decisions_of(
    demo: FurtherDemo,
    paper: FusionTable,
    step_of: Sequence[int],
    params: DecisionParams,
    segments: tuple[GoalSegment, ...] | None = None,
    *,
    corners: bool = False,
) -> list[DecisionPoint]:
    """Decision points of a further demo, the first demo's paper table replayed on its steps
    (``segments``: of these spans of its goal segments instead), each opening counted at its
    first onset (:attr:`DecisionParams.first_onset`).

    ``corners``: a correction's turns are decisions even where they read as corners (the way
    ahead and the other side closed at the opening's onset: :attr:`DecisionParams.skip_corners`
    off). A teacher who turned there had no other way; a person who took over had: their
    network drove on. A spur a few metres past a corner reads so (the sectors, held at the
    heading from before the corner, see its far wall ahead), and read as a corner the person's
    turn into it re-weights rows only. But a corner the person cut reads as a turn-off too (a
    decision added where there was no choice), so it is off unless asked for (the lesson
    ladder's corners rung, :mod:`lfdfuse.execute.lesson_check`)."""
    run = demo.run
    mapped = replace(run, segment_of=np.asarray(step_of, dtype=np.int64)[run.segment_of])
    fused = fused_vectors(paper, mapped, np.arange(len(run.t_ns)))
    shape = max(params.shape_steps, CORRECTION_SHAPE_STEPS) if demo.correction else params.shape_steps
    return find_decisions(
        segments=run.segments if segments is None else segments,
        demo=run.demo,
        informative=run.informative,
        fused=fused,
        track=demo.track,
        params=replace(
            params,
            first_onset=True,
            shape_steps=shape,
            skip_corners=params.skip_corners and not (corners and demo.correction),
        ),
    )


def _leaf_at(demo: FurtherDemo, step: str, i: int) -> str | None:
    """The sub-step of goal step ``step`` the network of correction ``demo`` was in at tick
    ``i`` (its name in the goal step's network), or None (no steps kept, or another step)."""
    if demo.steps is None:
        return None
    at = demo.steps[i]
    if at is None or not at.startswith(step + "/"):
        return None
    return at[len(step) + 1 :].split("/", 1)[0]


def _leaf_since(demo: FurtherDemo, step: str, leaf: str, i: int, lo: int) -> int:
    """The tick (at least ``lo``) the network of ``demo`` entered sub-step ``leaf`` of ``step``
    that it was in at tick ``i``: where its landmarks count from."""
    while i > lo and _leaf_at(demo, step, i - 1) == leaf:
        i -= 1
    return i


def inside_decision(
    demo: FurtherDemo,
    e: int,
    b: DecisionPoint,
    step: Step,
    seg: GoalSegment,
    paper: FusionTable,
    step_of: Sequence[int],
    params: DecisionParams,
    *,
    corners: bool = False,
) -> Inserted | None:
    """Correction ``demo``'s decision ``b`` as a decision of the sub-step its network was in when
    the turn began, its landmark counted from where the network entered that sub-step (found
    again from there, read as ``b`` was: ``corners``, :func:`decisions_of`); None when the
    network's step there is not one of ``step``'s."""
    at = b.begin if b.begin >= 0 else b.onset
    leaf = _leaf_at(demo, step.name, at)
    if leaf is None or step.network is None or leaf not in {s.name for s in step.network.steps}:
        return None
    since = _leaf_since(demo, step.name, leaf, at, seg.start)
    again = decisions_of(
        demo, paper, step_of, params, (GoalSegment(seg.index, since, seg.stop, seg.goal),), corners=corners
    )
    mine = next((d for d in again if d.side == b.side and abs(d.onset - b.onset) <= params.lookback), None)
    return None if mine is None else Inserted(leaf, mine, e)


def unique_steps(d: DecisionPoint, base: Step, taken: set[str]) -> list[Step]:
    """The landmark steps of decision ``d`` inserted before sub-step ``base`` (driving on with its
    rows, turning with none yet), named apart from ``taken`` (which then holds their names)."""
    k = 1
    while True:
        made = decision_steps(d, base, replace(base, fusion=()), "" if k == 1 else f"-{k}")
        if not {m.name for m in made} & taken:
            taken.update(m.name for m in made)
            return made
        k += 1


def labelled_parts(
    views: Sequence[SegmentedRun],
    others: Sequence[FurtherDemo],
    step_of: Sequence[Sequence[int]],
    j: int,
    old: Step,
    pos: Sequence[int],
    seen: Sequence[Mapping[int, DecisionPoint]],
    inserted: Sequence[Inserted],
    demos: Sequence[int],
) -> tuple[
    list[list[tuple[int, np.ndarray]]],
    list[tuple[list[tuple[int, np.ndarray]], list[tuple[int, np.ndarray]]]],
]:
    """The informative ticks of corrections ``demos`` in goal step ``j`` (whose sub-steps are
    ``old``'s) by the sub-step their network was in: per sub-step, and per inserted decision
    (drive on to its opening, turn). A person's turn the table's sub-goals also take
    (``seen``: per decision of the step, each demo's own decision there) is that sub-goal's turn, and what follows it the sub-steps after, whatever
    step the network, having missed it, was in."""
    assert old.network is not None
    names = [s.name for s in old.network.steps]
    extra: list[list[tuple[int, np.ndarray]]] = [[] for _ in names]
    ins_parts: list[tuple[list[tuple[int, np.ndarray]], list[tuple[int, np.ndarray]]]] = [
        ([], []) for _ in inserted
    ]
    turn_at = {2 * k + 1: n for n, p in enumerate(pos) for k in range(len(seen)) if p == 2 * k + 1}
    for e in demos:
        run, demo = views[e], others[e - 1]
        segs = [s for s, k in zip(run.segments, step_of[e], strict=True) if k == j]
        if not segs:
            continue
        seg = segs[0]
        where = np.full(len(run.t_ns), -1, dtype=np.int64)  # sub-step index per tick, -1: none
        for i in range(seg.start, seg.stop):
            at = _leaf_at(demo, old.name, i)
            if at in names:
                where[i] = names.index(at)
        for k, took in enumerate(seen):  # the table's turns the person took
            b = took.get(e)
            if b is None:
                continue
            n = turn_at[2 * k + 1]
            lo = b.begin if b.begin >= 0 else b.onset
            where[lo : b.turn_end] = n
            after = where[b.turn_end : seg.stop]
            after[(after >= 0) & (after <= n)] = min(n + 1, len(names) - 1)
        tag = np.full(len(run.t_ns), -1, dtype=np.int64)  # per tick: 2q drive / 2q+1 turn of inserted q
        for q, ins in enumerate(inserted):
            if ins.demo != e:
                continue
            d = ins.decision
            lo = d.begin if d.begin >= 0 else d.onset
            tag[d.since : lo] = 2 * q
            tag[lo : d.turn_end] = 2 * q + 1
        ticks = np.arange(seg.start, seg.stop)
        ticks = ticks[run.informative[ticks]]
        for q in range(len(inserted)):
            for half in (0, 1):
                got = ticks[tag[ticks] == 2 * q + half]
                if len(got):
                    ins_parts[q][half].append((e, got))
        rest = ticks[tag[ticks] < 0]
        for n in range(len(names)):
            got = rest[where[rest] == n]
            if len(got):
                extra[n].append((e, got))
    return extra, ins_parts
