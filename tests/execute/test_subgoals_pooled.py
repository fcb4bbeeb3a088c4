"""Sub-goals learned from several demos: the ring-spur demo pooled with itself.

The same demo twice (a copy under another name) finds the same decisions in both: every one is
merged, the landmarks are the single demo's, and every row of every step is estimated again on
twice the steps (``samples_added`` = the first demo's samples). The paper's estimate with 128
particles (as tests/execute/test_correction_fixes.py), unchecked, keeps it to a few seconds.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from lfdfuse.estimate.paper import PFParams
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.learn import LearnOptions, LearnResult, learn
from lfdfuse.network.table import named_leaf_steps

OPTS = EstimateOptions(seed=0, pf=replace(PFParams(), particles=128), smc=replace(SMCParams(), particles=128))
#: sub-goals learned from one demo, unchecked
ALONE = LearnOptions(OPTS, subgoals=True, check_starts=None)


@pytest.fixture(scope="module")
def refined(ring_spur_demo: Path) -> LearnResult:
    """The ring-spur demo learned alone with sub-goals (both tests compare with it)."""
    return learn([ring_spur_demo], options=ALONE)


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
    ring_spur_demo: Path, refined: LearnResult
) -> None:
    """The demo read as a correction of its own paper table (no sub-goals): every turn-off the
    sub-goal refinement finds in it is added to its goal step — drive on with the step's own
    rows, turn with the demo's turn alone, then the step's own rows again — each landmark as
    the refinement writes it."""
    from lfdfuse.estimate.pooled_subgoals import FurtherDemo, pool_subgoals
    from lfdfuse.estimate.subgoals import track_of
    from lfdfuse.segment.read import read_segmented_and_run

    run, raw = read_segmented_and_run(ring_spur_demo)
    track = track_of(raw, run)
    paper = learn([ring_spur_demo], options=LearnOptions(OPTS)).table
    res = pool_subgoals(
        first=run,
        first_name="demo",
        paper=paper,
        table=paper,
        decisions=(),
        others=[FurtherDemo("fix", run, track, correction=True)],
        opts=OPTS,
    )
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
