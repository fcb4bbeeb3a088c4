"""Sub-goals from several demos: decision points matched across demos, sub-step rows pooled.

The first demo's table with sub-goals (:func:`lfdfuse.estimate.subgoals.refine`, checked in its
world where it has one) is where this starts; every further demo is a teacher's demo or a
person's correction (a ``teleop --table`` log: only the person's ticks are informative).

* **Decisions** are found per demo (:func:`~lfdfuse.segment.decisions.find_decisions`, the first
  demo's paper table replayed on its steps) and **matched** to the first demo's by goal step and
  landmark (:func:`same_place`: the side, the opening's shape, the distance driven within a
  tolerance, the turn). A match is *merged*: the landmark stays the first demo's and the
  sub-steps' rows pool over both demos. A decision one teacher took and another teacher passed
  by while reaching the goal some other way was no choice the task needs: *dropped* (the goal
  step loses its sub-goals, the paper's step again).
* **A correction's goals are its network's**: a target its robot met while the network was after
  another goal (passed on the way, before the person took over or after the hand-back, or come
  round to again) starts no goal segment (:func:`~lfdfuse.estimate.sub_step_corrections.goals_of_network`),
  so the person's ticks go to the goal step the network was in.
* **A correction ends in a decision**: where the person took over and turned into an opening the
  network passed by, the turn is a decision of the goal step the network was in, with its
  landmark from the correction's own ticks and sensors — *added* to that step (a step whose
  sub-goals led elsewhere has them *replaced* by the person's). A correction's decision that
  matches one of the table's was missed by the network from the correction's start: it is
  merged and recognised by distance (the first opening on its side past a window that holds
  both demos' places) instead of by count. In a goal step that has sub-goals, a correction that
  kept its network's step (``/lfd/step``) is learned in the sub-step its network was in: its
  ticks re-weight that sub-step, its turn-offs become decisions there
  (:mod:`lfdfuse.estimate.sub_step_corrections`); without it, a turn-off replaces the step's.
* **Rows**: every leaf step keeps its rows; a row another demo adds informative steps to is
  estimated again on the pooled steps (the product over the demos, as
  :mod:`lfdfuse.estimate.pooled_estimate` does) on its own random stream, so a row nobody
  corrected is bit-identical. A new turn step's rows are the person's turn alone. A row the
  first demo pins that corrections add only a few ticks to (fewer than a row needs) stays as it
  is: one manoeuvre somewhere the row drives is no lesson for everywhere it drives.
* **The person's weight** (``weighing``, :mod:`lfdfuse.estimate.pooled_rows`): pooled, the
  demo's many steps in a row outweigh the person's ticks (a row of a thousand demo steps barely
  moves for 160 person ticks). In the goal steps the person took over, a row the person drove
  (a row's worth of ticks or more) can instead weigh the person's ticks ``even`` with the demo's
  (its steps thinned evenly to as many) or take the ``person``'s alone; ``pool`` (the default)
  is the product over every step, as above.
* **A correction's turns at corners** (``corners``): a teacher's turn where the way ahead and the
  other side are closed is a corner, no decision; read so, a person's turn into a spur just past
  a corner (its far wall seen ahead) is one too, and only re-weights rows. With ``corners`` a
  correction's turns are decisions there as well (:func:`~lfdfuse.estimate.sub_step_corrections.decisions_of`);
  off by default: a corner the person cut then reads as a decision nobody needed.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.commands import commands_of
from lfdfuse.estimate.demo_alignment import align
from lfdfuse.estimate.methods import EstimateOptions
from lfdfuse.estimate.pooled_rows import WEIGHINGS, Weighing, pooled_leaf
from lfdfuse.estimate.sub_step_corrections import (
    FurtherDemo,
    Inserted,
    decisions_of,
    goals_of_network,
    goals_once,
    inside_decision,
    labelled_parts,
    taken_over,
    unique_steps,
)
from lfdfuse.estimate.subgoals import decision_steps
from lfdfuse.network.landmark_goals import Landmark, OpeningCount
from lfdfuse.network.table import FusionTable, Network, Step
from lfdfuse.segment.decisions import DecisionParams, DecisionPoint, split_segments
from lfdfuse.segment.read import SegmentedRun

#: two decisions are one place when their distances from the sub-segment's start differ by at
#: most this share of the first's, or by ``MATCH_MIN_M`` ...
MATCH_SHARE = 0.3
MATCH_MIN_M = 1.5
#: ... and their turns by at most this
MATCH_TURN_RAD = math.radians(45.0)


@dataclass(frozen=True)
class Verdict:
    """What became of one decision: ``kept``, ``merged``, ``dropped``, ``added`` or ``replaced``."""

    kind: str
    step: str  # the goal step's name
    decision: DecisionPoint
    demos: tuple[str, ...]  # the demos that took it
    why: str

    def describe(self) -> str:
        d = self.decision
        where = "from the step's start" if d.at_start else f"at opening {d.nth}, {d.odometry_m:.1f} m"
        turn = f"turn {math.degrees(d.angle_rad):.0f}° {d.side} {where}"
        return f"{self.kind:8} {self.step}: {turn} ({', '.join(self.demos)}): {self.why}"


@dataclass(frozen=True)
class PooledSubgoals:
    table: FusionTable
    verdicts: tuple[Verdict, ...]
    decisions: tuple[DecisionPoint, ...]  # the first demo's decisions the table keeps


def same_place(a: DecisionPoint, b: DecisionPoint) -> bool:
    """Whether decisions ``a`` and ``b`` (of one goal step, in two demos) are the same turn-off:
    the same side and shape, the distance driven within a tolerance, a similar turn."""
    if a.side != b.side or a.at_start != b.at_start:
        return False
    if a.ahead_open is not None and b.ahead_open is not None and a.ahead_open != b.ahead_open:
        return False
    tol = max(MATCH_MIN_M, MATCH_SHARE * a.odometry_m, a.within_m or 0.0)
    return abs(a.odometry_m - b.odometry_m) <= tol and abs(a.angle_rad - b.angle_rad) <= MATCH_TURN_RAD


@dataclass
class _Slot:
    """One decision of a goal step's final sub-goals: the decision as the table writes it, the
    demo it comes from, and each demo's own decision there (for splitting its steps)."""

    decision: DecisionPoint
    source: int
    seen: dict[int, DecisionPoint] = field(default_factory=dict)
    by_distance: float | None = None  # merged from a correction: the window of a distance landmark


def pool_subgoals(
    *,
    first: SegmentedRun,
    first_name: str,
    paper: FusionTable,
    table: FusionTable,
    decisions: Sequence[DecisionPoint],
    others: Sequence[FurtherDemo],
    opts: EstimateOptions,
    params: DecisionParams = DecisionParams(),
    weighing: Weighing = "pool",
    corners: bool = False,
) -> PooledSubgoals:
    """``table`` (the first demo's with sub-goals, ``decisions`` its decision points; ``paper``
    the first demo's table without) with the further demos' decisions matched, added or dropped
    and the rows they drive in pooled, the corrections' ticks weighed by ``weighing`` in the goal
    steps their persons took over, their turns read as decisions even at corners with
    ``corners`` (see the module docstring)."""
    if weighing not in WEIGHINGS:
        raise ConfigError(f"weighing {weighing!r}: one of {', '.join(WEIGHINGS)}")
    over = taken_over(others) if weighing != "pool" else set()
    goals = {
        st.name: seg.goal
        for st, seg in zip(table.network.steps, first.segments, strict=False)
        if seg.goal is not None
    }
    others = [replace(o, run=_goals_met(o, goals)) if o.correction else o for o in others]
    runs = [first, *(o.run for o in others)]
    al = align(runs)
    n = len(first.segments)
    # a further demo's drive on past the first demo's last goal (a tour it did not make) is left out
    if al.goals[:n] != tuple(s.goal for s in first.segments) or any(g is not None for g in al.goals[n:]):
        raise ConfigError(
            f"with --subgoals every demo's goals are the first demo's ({first_name}): pool demos of"
            " other goals without --subgoals"
        )
    al = replace(al, step_of=tuple(tuple(k if k < n else -1 for k in m) for m in al.step_of))
    names = [first_name, *(o.name for o in others)]
    goal_steps = [s.index for s in first.segments if s.goal is not None]
    step_names = [s.name for s in table.network.steps]
    slots: dict[int, list[_Slot]] = {j: [] for j in range(len(first.segments))}
    for d in decisions:
        slots[d.segment].append(_Slot(d, 0, {0: d}))
    verdicts: list[Verdict] = []
    dropped: set[int] = set()  # goal steps back to the paper's step
    replaced: dict[int, int] = {}  # goal step -> the correction whose decisions it takes
    labelled: dict[int, set[int]] = {}  # goal step -> corrections whose ticks go by the network's sub-step
    inserted: dict[int, list[Inserted]] = {}  # goal step -> corrections' decisions inside its sub-steps
    for e, demo in enumerate(others, start=1):
        found = decisions_of(demo, paper, al.step_of[e], params, corners=corners)
        for j in goal_steps:
            mine = [d for d in found if al.step_of[e][d.segment] == j]
            segs = [s for s, k in zip(demo.run.segments, al.step_of[e], strict=True) if k == j]
            reached = any(s.goal == first.segments[j].goal for s in segs)
            have = slots[j]
            used: set[int] = set()
            unmatched: list[DecisionPoint] = []
            for b in mine:
                k = next((k for k, s in enumerate(have) if k not in used and same_place(s.decision, b)), None)
                if k is None:
                    unmatched.append(b)
                    continue
                used.add(k)
                have[k].seen[e] = b
                if demo.correction:
                    a = have[k].decision
                    have[k].by_distance = max(
                        have[k].by_distance or 0.0,
                        a.within_m or 0.0,
                        abs(a.odometry_m - b.odometry_m) + params.within_min_m,
                    )
            if demo.correction:
                step = table.network.steps[j]
                if demo.steps is not None and step.network is not None and j not in replaced and segs:
                    # the network's sub-step is known: a turn-off of the person's is a decision
                    # of the sub-step the network was in, the other ticks re-weight theirs
                    got = [
                        inside_decision(
                            demo, e, b, step, segs[0], paper, al.step_of[e], params, corners=corners
                        )
                        for b in unmatched
                    ]
                    if all(g is not None for g in got):
                        labelled.setdefault(j, set()).add(e)
                        inserted.setdefault(j, []).extend(g for g in got if g is not None)
                        continue
                if unmatched:
                    replaced[j] = e
                    slots[j] = [_Slot(b, e, {e: b}) for b in mine]
                continue
            if reached and (unmatched or len(used) < len(have)):
                dropped.add(j)
                for b in unmatched:
                    verdicts.append(
                        Verdict(
                            "dropped",
                            step_names[j],
                            b,
                            (demo.name,),
                            f"{first_name} reached {first.segments[j].goal} without it",
                        )
                    )
    out_slots: dict[int, list[_Slot]] = {}
    for j in goal_steps:
        if j in dropped and j not in replaced:
            for s in slots[j]:
                passed = [
                    names[e] for e in range(1, len(names)) if e not in s.seen and not others[e - 1].correction
                ]
                verdicts.append(
                    Verdict(
                        "dropped",
                        step_names[j],
                        s.decision,
                        tuple(names[e] for e in sorted(s.seen)),
                        f"{', '.join(passed) or 'another demo'} passed it by and reached the goal some other way",
                    )
                )
            out_slots[j] = []
            continue
        out_slots[j] = slots[j]
        for s in slots[j]:
            took = tuple(names[e] for e in sorted(s.seen))
            if j in replaced:
                kind, why = (
                    ("added", "the person turned off where the network drove on")
                    if not any(d.segment == j for d in decisions)
                    else ("replaced", "the person turned off elsewhere than the table's sub-goals")
                )
            elif len(s.seen) > 1:
                kind = "merged"
                why = "the same place in every demo that took it"
                if s.by_distance is not None:
                    why = f"the network missed it; now the first such opening past {s.decision.odometry_m:.1f} ± {s.by_distance:.1f} m"
            else:
                kind, why = "kept", "only the first demo took it; no other passed it by to the goal"
            verdicts.append(Verdict(kind, step_names[j], s.decision, took, why))
        if j in dropped and j not in replaced:
            continue
        for ins in inserted.get(j, []):
            verdicts.append(
                Verdict(
                    "added",
                    f"{step_names[j]}/{ins.leaf}",
                    ins.decision,
                    (names[ins.demo],),
                    "the person turned off where the network, in this sub-step, drove on",
                )
            )
    built = _build(
        first,
        paper,
        table,
        others,
        al.step_of,
        out_slots,
        opts,
        names,
        {j: v for j, v in labelled.items() if j not in dropped or j in replaced},
        inserted,
        {name: weighing for name in over},
    )
    kept = tuple(s.decision for j in goal_steps for s in out_slots[j] if s.source == 0)
    return PooledSubgoals(built, tuple(verdicts), kept)


def _goals_met(demo: FurtherDemo, goals: Mapping[str, str]) -> SegmentedRun:
    """A correction's run segmented by the goals its network met (``goals``: each goal step's
    goal by name), or, where the log kept no network steps, by each goal met once."""
    if demo.steps is None:
        return goals_once(demo.run)
    return goals_of_network(demo.run, demo.steps, goals)


def _build(
    first: SegmentedRun,
    paper: FusionTable,
    table: FusionTable,
    others: Sequence[FurtherDemo],
    step_of: Sequence[Sequence[int]],
    slots: dict[int, list[_Slot]],
    opts: EstimateOptions,
    names: Sequence[str],
    labelled: dict[int, set[int]],
    inserted: dict[int, list[Inserted]],
    weighings: Mapping[str, Weighing],
) -> FusionTable:
    """The table with each goal step's final sub-goals (``slots``), every leaf's rows pooled;
    ``labelled``: per goal step the corrections whose ticks go to the sub-step the network was
    in, ``inserted`` their decisions inside sub-steps; ``weighings``: per goal step (by name)
    how the corrections' ticks weigh in its rows where not ``pool``."""
    runs = [first, *(o.run for o in others)]
    models = [
        commands_of(run, requested=opts.commands, recheck_s=opts.model.recheck_s, nudge_s=opts.model.nudge_s)
        for run in runs
    ]
    views = [
        run if m.decisions is None else replace(run, informative=run.informative & m.decisions)
        for run, m in zip(runs, models, strict=True)
    ]
    corrections = {e for e, o in enumerate(others, start=1) if o.correction}
    count = 0
    weighing: Weighing = "pool"

    def leaf(base: Step, parts: Sequence[tuple[int, np.ndarray]]) -> Step:
        nonlocal count
        count += 1
        return pooled_leaf(count - 1, base, parts, views, models, opts, corrections, weighing)

    built: list[Step] = []
    for j, old in enumerate(table.network.steps):
        weighing = weighings.get(old.name, "pool")
        mine = slots.get(j)
        whole = [(e, t) for e in range(len(runs)) if len(t := _ticks(views[e], step_of[e], j))]
        if mine is None or not mine:
            # a tour, a goal step without sub-goals, or one whose sub-goals were dropped (the paper's)
            built.append(leaf(old if mine is None or old.network is None else paper.network.steps[j], whole))
            continue
        by_step = labelled.get(j, set()) if all(s.source == 0 for s in mine) else set()
        sub = _sub_parts(views, step_of, j, mine, skip=by_step)
        inner: list[Step] = []
        if all(s.source == 0 for s in mine):  # the table's sub-goals, matched in other demos
            assert old.network is not None
            olds = list(old.network.steps)
            pos: list[int] = []  # each sub-step's sub-segment
            for k, s in enumerate(mine):
                pos += [2 * k, 2 * k + 1] if not s.decision.at_start else [2 * k + 1]
            pos.append(2 * len(mine))
            mine_ins = sorted(
                (i for i in inserted.get(j, []) if i.demo in by_step),
                key=lambda i: (i.demo, i.decision.onset),
            )
            extra, ins_parts = labelled_parts(
                views, others, step_of, j, old, pos, [s.seen for s in mine], mine_ins, sorted(by_step)
            )
            taken = {st.name for st in olds}
            for n, (st, p) in enumerate(zip(olds, pos, strict=True)):
                for q, ins in enumerate(mine_ins):
                    if ins.leaf != st.name:
                        continue
                    made = unique_steps(ins.decision, st, taken)
                    drive_parts, turn_parts = ins_parts[q]
                    if not ins.decision.at_start:
                        inner.append(leaf(made[0], sub[p] + drive_parts))
                    inner.append(leaf(made[-1], turn_parts))
                if p % 2 == 0 and p < 2 * len(mine) and mine[p // 2].by_distance is not None:
                    st = replace(st, landmark=_by_distance(st.landmark, mine[p // 2].by_distance or 0.0))
                inner.append(leaf(st, sub[p] + extra[n]))
        else:  # the correction's: drive on with the step's own rows, turn as the person did
            base = old if old.network is None else paper.network.steps[j]
            own = [(e, t) for e, t in whole if e == 0]
            for k, s in enumerate(mine):
                tag = f"-{k + 1}" if len(mine) > 1 else ""
                made = decision_steps(s.decision, base, replace(base, fusion=()), tag)
                if not s.decision.at_start:
                    inner.append(leaf(made[0], own + sub[2 * k]))
                inner.append(leaf(made[-1], sub[2 * k + 1]))
            inner.append(leaf(replace(base, name=old.name), own + sub[-1]))
        built.append(Step(old.name, old.goal, (), Network(old.name, tuple(inner))))
    by = dict(table.estimated_by)
    by["sources"] = list(names)
    by["source_commands"] = [m.mode for m in models]
    return replace(table, network=replace(table.network, steps=tuple(built)), estimated_by=by)


def _ticks(run: SegmentedRun, step_of: Sequence[int], j: int) -> np.ndarray:
    """The informative steps of ``run`` in its goal segments matched to network step ``j``."""
    segs = [s.index for s, k in zip(run.segments, step_of, strict=True) if k == j]
    return np.nonzero(np.isin(run.segment_of, segs) & run.informative)[0]


def _sub_parts(
    views: Sequence[SegmentedRun],
    step_of: Sequence[Sequence[int]],
    j: int,
    slots: Sequence[_Slot],
    skip: Collection[int] = (),
) -> list[list[tuple[int, np.ndarray]]]:
    """Per sub-segment of goal step ``j`` (drive, turn per decision, then the rest) the
    informative steps of every demo that took each of its decisions (split at its own), but
    those in ``skip``."""
    out: list[list[tuple[int, np.ndarray]]] = [[] for _ in range(2 * len(slots) + 1)]
    for e, run in enumerate(views):
        if e in skip or not all(e in s.seen for s in slots):
            continue  # a demo that did not take every decision of the step cannot be split like it
        segs = [s for s, k in zip(run.segments, step_of[e], strict=True) if k == j]
        for seg in segs[:1]:
            own = [replace(s.seen[e], segment=seg.index) for s in slots]
            subs = split_segments((seg,), own)
            for i, (_, sub) in enumerate(subs):
                ticks = np.arange(sub.start, sub.stop)
                ticks = ticks[run.informative[ticks]]
                if len(ticks):
                    out[i].append((e, ticks))
    return out


def _by_distance(mark: Landmark | None, within_m: float) -> Landmark | None:
    """The opening landmark ``mark`` met by distance: the first opening on its side past
    ``odometry_m − within_m``."""
    if mark is None or mark.kind != "opening" or mark.odometry_m is None:
        return mark
    return replace(mark, within_m=round(within_m, 2), count=OpeningCount.ALL)
