"""Sub-goals learned from several demos: the ring-spur demo pooled with itself.

The same demo twice (a copy under another name) finds the same decisions in both: every one is
merged, the landmarks are the single demo's, and every row of every step is estimated again on
twice the steps (``samples_added`` = the first demo's samples). The paper's estimate with 128
particles (as tests/execute/test_correction_fixes.py), unchecked, keeps it to a few seconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lfdfuse import learn as learning
from lfdfuse.estimate.paper import PFParams
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.pooled_subgoals import PooledSubgoals, pool_subgoals
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.estimate.sub_step_corrections import FurtherDemo
from lfdfuse.learn import LearnOptions, LearnResult, learn
from lfdfuse.network.table import FusionTable, named_leaf_steps
from lfdfuse.segment.decisions import DecisionPoint
from lfdfuse.segment.read import SegmentedRun
from lfdfuse.segment.track import LandmarkTrack
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import World
from lfdfuse.world.parse import parse_world

OPTS = EstimateOptions(seed=0, pf=replace(PFParams(), particles=128), smc=replace(SMCParams(), particles=128))
#: sub-goals learned from one demo, unchecked
ALONE = LearnOptions(OPTS, subgoals=True, check_starts=None)


@pytest.fixture(scope="module")
def refined(ring_spur_demo: Path) -> LearnResult:
    """The ring-spur demo learned alone with sub-goals (both tests compare with it)."""
    return learn([ring_spur_demo], options=ALONE)


@dataclass(frozen=True)
class Read:
    """The ring-spur demo read with its landmark track, and its paper table (no sub-goals)."""

    run: SegmentedRun
    track: LandmarkTrack
    paper: FusionTable

    def pool(
        self,
        table: FusionTable,
        decisions: Sequence[DecisionPoint],
        fix: SegmentedRun,
        *,
        correction: bool = True,
        steps: tuple[str, ...] | None = None,
        **how: Any,
    ) -> PooledSubgoals:
        """``table`` (the demo's, ``decisions`` its decision points) pooled with ``fix``, a
        further demo in the demo's world (a correction unless said)."""
        return pool_subgoals(
            first=self.run,
            first_name="demo",
            paper=self.paper,
            table=table,
            decisions=decisions,
            others=[FurtherDemo("fix", fix, self.track, correction=correction, steps=steps)],
            opts=OPTS,
            **how,
        )


@pytest.fixture(scope="module")
def read(ring_spur_demo: Path) -> Read:
    from lfdfuse.estimate.subgoals import track_of
    from lfdfuse.segment.read import read_segmented_and_run

    run, raw = read_segmented_and_run(ring_spur_demo)
    return Read(run, track_of(raw, run), learn([ring_spur_demo], options=LearnOptions(OPTS)).table)


def test_a_demo_pooled_with_itself_merges_every_decision_and_doubles_every_sub_step(
    tmp_path: Path, ring_spur_demo: Path, refined: LearnResult
) -> None:
    one = refined
    twin = tmp_path / "twin.seg.mcap"
    twin.write_bytes(ring_spur_demo.read_bytes())
    two = learn([ring_spur_demo, twin], options=ALONE)
    assert one.decisions and two.decisions == one.decisions
    assert [v.kind for v in two.verdicts] == ["merged"] * len(one.decisions)
    assert all(v.demos == (ring_spur_demo.name, "twin.seg.mcap") for v in two.verdicts)
    a, b = named_leaf_steps(one.table), named_leaf_steps(two.table)
    assert [(n, s.landmark) for n, s in a] == [(n, s.landmark) for n, s in b]  # the same sub-goals
    for (name, s), (_, t) in zip(a, b, strict=True):
        assert [r.bac for r in s.fusion] == [r.bac for r in t.fusion], name
        for r, q in zip(s.fusion, t.fusion, strict=True):
            assert q.samples == 2 * r.samples and q.samples_added == r.samples, (name, r.bac)
            assert q.weights_before == r.weights
    assert two.table.estimated_by["sources"] == [ring_spur_demo.name, "twin.seg.mcap"]


def test_a_corrections_turn_off_becomes_a_decision_of_a_table_without_one(
    read: Read, refined: LearnResult
) -> None:
    """The demo read as a correction of its own paper table (no sub-goals): every turn-off the
    sub-goal refinement finds in it is added to its goal step — drive on with the step's own
    rows, turn with the demo's turn alone, then the step's own rows again — each landmark as
    the refinement writes it."""
    run, paper = read.run, read.paper
    res = read.pool(paper, (), run)
    assert [(v.kind, v.decision) for v in res.verdicts] == [("added", d) for d in refined.decisions]
    assert res.decisions == ()  # none of the first demo's own
    marks = [(n, s.landmark) for n, s in named_leaf_steps(res.table)]
    assert marks == [(n, s.landmark) for n, s in named_leaf_steps(refined.table)]
    plain = {s.name: s for s in paper.network.steps}
    for step in res.table.network.steps:
        if step.network is None:
            continue
        *drive, turn, rest = step.network.steps
        base = plain[step.name]
        assert rest.name == base.name and [r.bac for r in rest.fusion] == [r.bac for r in base.fusion]
        assert all(r.samples_added for r in turn.fusion) and all(
            r.weights_before is None for r in turn.fusion
        )
        for leaf in (*drive, rest):  # the step's own rows, with the "person's" steps there added
            assert {r.bac for r in base.fusion} <= {r.bac for r in leaf.fusion}


def _ring(passage: bool) -> World:
    """A 22 × 14 m corridor ring, red on its south corridor, green on its north one; with
    ``passage`` a corridor through the middle joins them (the short way to green)."""
    outer = [[0, 0], [22, 0], [22, 14], [0, 14], [0, 0]]
    blocks = (
        [
            [[2.4, 2.4], [9.8, 2.4], [9.8, 11.6], [2.4, 11.6], [2.4, 2.4]],
            [[12.2, 2.4], [19.6, 2.4], [19.6, 11.6], [12.2, 11.6], [12.2, 2.4]],
        ]
        if passage
        else [[[2.4, 2.4], [19.6, 2.4], [19.6, 11.6], [2.4, 11.6], [2.4, 2.4]]]
    )
    return parse_world(
        {
            "name": "ring-passage" if passage else "ring-closed",
            "walls": [outer, *blocks],
            "targets": [
                {"name": "red", "position": [7.0, 1.2], "radius": 0.25},
                {"name": "green", "position": [17.0, 12.8], "radius": 0.25},
            ],
            "start": [1.5, 1.2, 0.0],
        }
    )


def test_a_turn_off_one_teacher_took_and_another_passed_by_to_the_goal_is_dropped(tmp_path: Path) -> None:
    """Two teachers of red then green: one where a passage joins the ring's corridors (it turns
    into it and out at the top: two decisions), one where it is walled off (round the ring:
    corners only). Both reached green, so the turns were no choice the task needs: dropped,
    and the table is the paper's (one step per goal, its rows pooled over both demos as
    without sub-goals)."""
    legs = (Leg("red", "keep-center"), Leg("green", "keep-center"))
    demos = [
        learning.demonstrate(
            legs, world=_ring(p), folder=tmp_path, name=n, duration_s=200.0, seed=1
        ).segmented
        for p, n in ((True, "passage"), (False, "round"))
    ]
    res = learn(demos, options=ALONE)
    assert res.verdicts and {v.kind for v in res.verdicts} == {"dropped"}
    assert {v.step for v in res.verdicts} == {"reach-green"}
    assert all(
        v.demos == ("passage.seg.mcap",) and "round.seg.mcap passed it by" in v.why for v in res.verdicts
    )
    assert res.decisions == ()
    assert [s.name for s in res.table.network.steps] == ["reach-red", "reach-green"]
    assert all(s.network is None and s.landmark is None for s in res.table.network.steps)
    pooled = learn(demos, options=LearnOptions(OPTS)).table  # without sub-goals
    assert [[(r.bac, r.samples) for r in s.fusion] for s in res.table.network.steps] == [
        [(r.bac, r.samples) for r in s.fusion] for s in pooled.network.steps
    ]  # the same rows on the same steps of both demos


def _labels(run: SegmentedRun, table: FusionTable, decisions: Sequence[DecisionPoint]) -> tuple[str, ...]:
    """The network step of every tick of ``run`` as ``table``'s runtime would name it had it
    driven the teacher's path: each goal step's sub-steps switched where its decisions are."""
    out: list[str] = []
    for seg, step in zip(run.segments, table.network.steps, strict=True):
        names = [step.name] * (seg.stop - seg.start)
        if step.network is not None:
            leaves = iter(s.name for s in step.network.steps)
            at = seg.start
            for d in (d for d in decisions if d.segment == seg.index):
                begin = d.begin if d.begin >= 0 else d.onset
                if not d.at_start:
                    names[at - seg.start : begin - seg.start] = [f"{step.name}/{next(leaves)}"] * (begin - at)
                names[begin - seg.start : d.turn_end - seg.start] = [f"{step.name}/{next(leaves)}"] * (
                    d.turn_end - begin
                )
                at = d.turn_end
            names[at - seg.start :] = [f"{step.name}/{next(leaves)}"] * (seg.stop - at)
        out += names
    return tuple(out)


def test_a_correction_in_a_sub_step_re_weights_that_sub_step_alone(read: Read, refined: LearnResult) -> None:
    """The demo read as a correction of its own table with sub-goals in which the person drove
    only some way past the turn into the spur (the network's sub-step there: the goal step's last,
    ``reach-green/reach-green``). Known from ``/lfd/step``, the person's ticks re-weight that
    sub-step's rows; every other row of every step stays bit for bit, the sub-goals too. Not
    known (a log segmented without it), the correction took none of the step's decisions and
    teaches nothing."""
    run = read.run
    table = refined.table
    (d,) = [d for d in refined.decisions if table.network.steps[d.segment].name == "reach-green"]
    seg = run.segments[d.segment]
    person = np.zeros(len(run.t_ns), dtype=bool)
    person[d.turn_end + 30 : seg.stop] = True  # past the turn
    fix = replace(run, informative=run.informative & person)
    steps = _labels(run, table, refined.decisions)
    assert {steps[i] for i in np.flatnonzero(person)} == {"reach-green/reach-green"}

    def pooled(known: bool) -> FusionTable:
        return read.pool(table, refined.decisions, fix, steps=steps if known else None).table

    assert pooled(False).network == table.network
    a, b = named_leaf_steps(table), named_leaf_steps(pooled(True))
    assert [(n, s.landmark) for n, s in a] == [(n, s.landmark) for n, s in b]
    driven = {int(x) for x in run.bac[np.flatnonzero(fix.informative)]}
    changed = {
        (n, r.bac)
        for (n, s), (_, t) in zip(a, b, strict=True)
        for r, q in zip(s.fusion, t.fusion, strict=False)
        if r != q
    }
    assert changed and {n for n, _ in changed} == {"reach-green/reach-green"}
    assert {bac for _, bac in changed} <= driven
    for (n, s), (_, t) in zip(a, b, strict=True):
        assert len(s.fusion) == len(t.fusion) or n == "reach-green/reach-green"
        rows = {r.bac: r for r in t.fusion}
        for r in s.fusion:
            q = rows[r.bac]
            assert q == r or (q.samples_added and q.weights_before == r.weights), (n, r.bac)


def test_the_persons_weight_moves_only_rows_they_drove_enough_in_where_they_took_over(
    read: Read, refined: LearnResult
) -> None:
    """The correction of the test before (the person past the turn into the spur, in reach-green's
    last sub-step) pooled with each weighing: ``pool`` is the default's table; ``even`` and
    ``person`` change only rows the person drove ``min_samples`` ticks or more in, there estimated
    on as many demo steps as person ticks (fewer where the demo has fewer) or on the person's
    alone; every other row, step and landmark is the pooled table's, bit for bit."""
    run = read.run
    table = refined.table
    (d,) = [d for d in refined.decisions if table.network.steps[d.segment].name == "reach-green"]
    seg = run.segments[d.segment]
    person = np.zeros(len(run.t_ns), dtype=bool)
    person[d.turn_end + 30 : seg.stop] = True
    fix = replace(run, informative=run.informative & person)
    steps = _labels(run, table, refined.decisions)

    def pooled(**weighing: str) -> FusionTable:
        return read.pool(table, refined.decisions, fix, steps=steps, **weighing).table

    pool = pooled()
    assert pooled(weighing="pool") == pool
    drove = np.bincount(run.bac[fix.informative], minlength=64)
    moved = set()
    for weighing in ("even", "person"):
        got = pooled(weighing=weighing)
        a, b = named_leaf_steps(pool), named_leaf_steps(got)
        assert [(n, s.landmark) for n, s in a] == [(n, s.landmark) for n, s in b]
        for (n, s), (_, t) in zip(a, b, strict=True):
            rows = {r.bac: r for r in t.fusion}
            assert sorted(rows) == [r.bac for r in s.fusion]
            for r in s.fusion:
                q = rows[r.bac]
                if n != "reach-green/reach-green" or drove[r.bac] < OPTS.min_samples:
                    assert q == r, (weighing, n, r.bac)
                    continue
                moved.add(weighing)
                mine = int(drove[r.bac])
                demo = (r.samples or 0) - mine  # the pooled row: the demo's steps and the person's
                assert q.samples == (mine if weighing == "person" else mine + min(demo, mine))
    assert moved == {"even", "person"}


def test_a_persons_few_ticks_leave_a_row_the_demo_pins_as_it_was(read: Read, refined: LearnResult) -> None:
    """The demo read as a correction in the goal step's last sub-step, the person driving from
    several places past the turn on: each row of that sub-step the person added fewer ticks to
    than a row needs (``min_samples``) while the demo's own row has that many stays bit for bit;
    every other row the person drove is estimated again on the pooled ticks. Over several
    stretches, so both kinds of row come up."""
    run = read.run
    table = refined.table
    (d,) = [d for d in refined.decisions if table.network.steps[d.segment].name == "reach-green"]
    seg = run.segments[d.segment]
    steps = _labels(run, table, refined.decisions)
    (old,) = [s for n, s in named_leaf_steps(table) if n == "reach-green/reach-green"]
    kinds: set[bool] = set()
    for lo in range(d.turn_end + 30, seg.stop - 20, max((seg.stop - d.turn_end) // 4, 1)):
        person = np.zeros(len(run.t_ns), dtype=bool)
        person[lo : seg.stop] = True
        fix = replace(run, informative=run.informative & person)
        pooled = read.pool(table, refined.decisions, fix, steps=steps).table
        (new,) = [s for n, s in named_leaf_steps(pooled) if n == "reach-green/reach-green"]
        rows = {r.bac: r for r in new.fusion}
        added = np.bincount(run.bac[fix.informative], minlength=max(rows) + 1)
        for r in old.fusion:
            few = 0 < added[r.bac] < OPTS.min_samples <= (r.samples or 0)
            if added[r.bac]:
                kinds.add(few)
                assert (rows[r.bac] == r) == few, (lo, r.bac, int(added[r.bac]), r.samples)
                assert few or rows[r.bac].samples_added == added[r.bac]
    assert kinds == {True, False}


def test_a_corrections_turn_off_inside_a_sub_step_becomes_a_decision_of_that_sub_step(
    read: Read, refined: LearnResult
) -> None:
    """The demo as a correction of its own table with sub-goals whose reach-green decision is
    put 30 m farther on (so the teacher's turn into the spur is none of the table's), its
    network (``/lfd/step``) already in the goal step's last sub-step throughout reach-green: the
    person's turn becomes a decision of that sub-step, its landmark counted from where the
    network entered it — the demo's own, since that is reach-green's start — and inserted before
    it; the table's sub-goals and every row the person did not drive stay bit for bit."""
    run, table = read.run, refined.table
    (d,) = [d for d in refined.decisions if table.network.steps[d.segment].name == "reach-green"]
    far = replace(d, odometry_m=d.odometry_m + 30.0)
    decisions = tuple(far if x == d else x for x in refined.decisions)
    seg = run.segments[d.segment]
    steps = list(_labels(run, table, refined.decisions))
    steps[seg.start : seg.stop] = ["reach-green/reach-green"] * (seg.stop - seg.start)
    person = np.zeros(len(run.t_ns), dtype=bool)
    person[seg.start : seg.stop] = True
    fix = replace(run, informative=run.informative & person)
    res = read.pool(table, decisions, fix, steps=tuple(steps))
    (added,) = [v for v in res.verdicts if v.kind == "added"]
    assert added.step == "reach-green/reach-green" and added.demos == ("fix",)
    got = added.decision
    assert (got.side, got.nth, got.since, got.onset, got.odometry_m) == (
        d.side,
        d.nth,
        d.since,
        d.onset,
        d.odometry_m,
    )
    before = dict(named_leaf_steps(table))
    after = dict(named_leaf_steps(res.table))
    new = [n for n in after if n not in before]
    assert new == ["reach-green/to-left-opening-1-2", "reach-green/turn-left-2"]
    names = [n for n, _ in named_leaf_steps(res.table)]
    assert names.index(new[1]) + 1 == names.index("reach-green/reach-green")  # right before that sub-step
    assert after[new[0]].landmark == before["reach-green/to-left-opening-1"].landmark
    turn = after[new[1]]
    assert turn.fusion and all(r.weights_before is None and r.samples_added == r.samples for r in turn.fusion)
    for n, s in before.items():  # the table's sub-goals as they were; rows only where the person drove
        assert after[n].landmark == s.landmark, n
        if not n.startswith("reach-green/reach-green"):
            assert after[n] == s, n


def test_a_corrections_turns_at_corners_are_decisions_only_when_asked(
    read: Read, refined: LearnResult
) -> None:
    """The demo read as a correction of its own paper table, as in the test above: by default
    (``corners`` off) a turn into a corner is none of the added decisions, bit for bit the table
    of a call without the option; with ``corners`` every turn the default adds is added still,
    and the teacher's corners too (the way ahead and the other side closed: there was no other
    way, but a person who took over had — their network drove on). A teacher's demo pooled is
    read as before either way: the option reads corrections only."""
    run, paper = read.run, read.paper

    def pooled(correction: bool, **corners: bool) -> tuple[FusionTable, list[tuple[str, DecisionPoint]]]:
        res = read.pool(paper, (), run, correction=correction, **corners)
        return res.table, [(v.kind, v.decision) for v in res.verdicts]

    plain = pooled(True)
    assert pooled(True, corners=False) == plain
    assert [k for k, _ in plain[1]] == ["added"] * len(refined.decisions)
    table, verdicts = pooled(True, corners=True)
    assert {k for k, _ in verdicts} == {"added"} and len(verdicts) > len(plain[1])
    got = {(d.segment, d.side, d.onset) for _, d in verdicts}
    assert {(d.segment, d.side, d.onset) for _, d in plain[1]} <= got
    assert table != plain[0]
    assert pooled(False, corners=True) == pooled(False)
