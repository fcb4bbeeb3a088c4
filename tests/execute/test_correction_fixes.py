"""Where a learned table fails, one scripted correction and a re-estimate fix it.

The ring-spur task learned without sub-goals (:mod:`tests.support.offroute`: seed 1 demo,
seed 0 estimate) reaches red and green, then shuttles in the dead-end spur after green and never
reaches blue. A person takes over once from the teacher's start (``teleop --table --input script
--script tests/sources/teleop/ring-spur-fix.yaml``), drives out of the spur toward blue and hands
back; ``segment`` (the table's behaviours, ``--commands continuous``) and ``estimate demo fix``
pool the two logs. Every
row that changes is a (step, BAC) row the person drove in (measured: all 5 of them, in step
reach-blue), every other row is bit-identical, and the fixed table completes the task from the
failed start and from two perturbed ones, without a collision.

Run time: about 38 s on 2 cores shared with other work (load 4), most of it the four runs of
the task (a 300 s failure, three ~245 s completions) and two segmentations. Both estimates run
the default pf estimator (seed 0) with 128 particles instead of 384: the numbers are the same
with either (the same failure, the same 5 rows changed, 3/3 starts complete, 0 collisions), and
the two estimates take about 6 s instead of 18. Only the failing run is bounded by the task's
300 s; the fixed runs end when the task completes (about 245 s simulated).

The script holds three exact twists, so ``segment --commands auto`` reads it as a person's few
held commands (discrete): then a held command is evidence where it is pressed, not at every
tick, and the correction adds 21 samples instead of 183 — too few to fix the table (0 of 3
starts). Its author means every tick of those twists: the drive mapping reads it so.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.estimate.paper import PFParams
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.learn import LearnOptions, learn
from lfdfuse.network.table import FusionTable, dump_table, load_table, named_leaf_steps
from lfdfuse.segment.read import network_ticks, read_segmented
from lfdfuse.world.model import load_world
from tests.conftest import ROOT
from tests.support.offroute import CASES, perturbed_starts, run_starts

FIX_SCRIPT = ROOT / "tests" / "sources" / "teleop" / "ring-spur-fix.yaml"

#: particles per row of both estimates (the command line's default is 384; see above)
PARTICLES = 128

runner = CliRunner()


def _cli(*args: str) -> None:
    res = runner.invoke(app, list(args))
    assert res.exit_code == 0, res.output


def _rows(table: FusionTable) -> dict[tuple[str | None, int], object]:
    """Every row of a table by (its step's goal, its BAC)."""
    return {(s.goal, r.bac): r for _, s in named_leaf_steps(table) for r in s.fusion}


def test_one_scripted_correction_fixes_the_ring_spur_table_and_changes_only_its_rows(
    tmp_path: Path, ring_spur_demo: Path
) -> None:
    case = CASES["ring-spur"]
    demo = ring_spur_demo  # the teacher's, seed 1
    # learned as `estimate demo.seg.mcap --particles 128` does, without sub-goals, seed 0
    opts = EstimateOptions(
        seed=0,
        pf=replace(PFParams(), particles=PARTICLES),
        smc=replace(SMCParams(), particles=PARTICLES),
    )
    (tmp_path / "T.yaml").write_text(dump_table(learn([demo], options=LearnOptions(opts)).table))
    table = load_table(tmp_path / "T.yaml")  # as teleop --table and the comparison read it
    starts = perturbed_starts(load_world(case.world), 2, seed=0)

    # the learned table fails from the teacher's start: green, then caught in the spur
    (before,) = run_starts(table, case, starts=starts[:1], folder=tmp_path, label="before")
    assert not before["completed"] and before["reached"] == "red,green", before

    # one scripted correction from the teacher's start, through the command line
    fix = tmp_path / "fix.mcap"
    _cli(
        "teleop",
        "--table",
        str(tmp_path / "T.yaml"),
        "--world",
        case.world,
        "--input",
        "script",
        "--script",
        str(FIX_SCRIPT),
        "-o",
        str(fix),
    )
    behaviors = ",".join(table.behaviors)
    _cli(
        "segment",
        str(fix),
        "--behaviors",
        behaviors,
        "--commands",
        "continuous",
        "-o",
        str(tmp_path / "fix.seg.mcap"),
    )
    _cli(
        "estimate",
        str(demo),
        str(tmp_path / "fix.seg.mcap"),
        "--particles",
        str(PARTICLES),
        "-o",
        str(tmp_path / "fixed.yaml"),
    )
    fixed = load_table(tmp_path / "fixed.yaml")

    # the (goal, BAC) rows the person drove in, from who drove each tick (/lfd/authority)
    run = read_segmented(tmp_path / "fix.seg.mcap")
    network = network_ticks(fix, run.t_ns)
    assert network is not None
    person = np.flatnonzero(~network & run.informative)
    assert len(person) > 0
    driven = {(run.segments[run.segment_of[i]].target, int(run.bac[i])) for i in person}
    assert {goal for goal, _ in driven} == {"blue"}  # out of the spur toward blue: step reach-blue

    old, new = _rows(table), _rows(fixed)
    changed = {key for key in new if old.get(key) != new[key]}
    assert old.keys() <= new.keys()
    assert changed and changed <= driven, (changed, driven)
    for key in old.keys() - changed:
        assert new[key] == old[key]  # rows elsewhere bit-identical (as written and read back)
    # the steps the person never drove in keep their default weights too
    for (_, a), (_, b) in zip(named_leaf_steps(table), named_leaf_steps(fixed), strict=True):
        if not any(goal == a.goal for goal, _ in driven):
            assert b.default_weights == a.default_weights and b.fusion == a.fusion

    # the fixed table completes the task from the failed start and two perturbed ones
    after = run_starts(fixed, case, starts=starts, folder=tmp_path, label="after")
    assert [r["completed"] for r in after] == [True, True, True], after
    assert all(r["collisions"] == 0 for r in after), after
