"""Teach again: where a table learned with sub-goals fails, one correction and a re-estimate.

In the generated off-route world of a seed (:mod:`tests.support.generated_worlds`) the scripted
teacher demonstrates the three-goal task once; the demo is learned with sub-goals, checked in its
world (``estimate --subgoals``), and the table runs from :data:`STARTS` perturbed starts. From the
first start that fails, a scripted person corrects it once (:mod:`tests.support.corrections`:
the teacher's path where the robot left it); the demo and the correction are estimated together
with sub-goals (``estimate demo.seg.mcap corr.seg.mcap --subgoals``) and the new table runs from
the same starts. :func:`teach_again` is one world; the ``corrections`` bench many.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse import learn
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.execute.starts import perturbed_starts
from lfdfuse.log.reader import read_run
from lfdfuse.network.table import FusionTable
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.read import read_segmented
from tests.support.corrections import record_correction
from tests.support.generated import THREE_GOALS, TIME_FACTOR
from tests.support.generated_worlds import generate_offroute
from tests.support.offroute import OffRouteCase, run_starts

#: the starts every table runs from: the failing one and (at least) three others
STARTS = 4


@dataclass(frozen=True)
class TaughtAgain:
    """One world: the table's runs before, the correction (from the first failing start), after."""

    seed: int
    demo_completed: bool
    before: tuple[bool, ...] = ()
    failing: int | None = None  # index of the start corrected
    corrected: bool = False  # a correction was recorded (the failing run left the teacher's path)
    after: tuple[bool, ...] = ()
    verdicts: tuple[str, ...] = ()
    table_before: FusionTable | None = field(default=None, compare=False)
    table_after: FusionTable | None = field(default=None, compare=False)

    @property
    def fixed(self) -> bool:
        """The failing start completes after, and at least two of the three others."""
        if self.failing is None or not self.after:
            return False
        others = [ok for k, ok in enumerate(self.after) if k != self.failing]
        return self.after[self.failing] and sum(others) >= 2

    @property
    def regressions(self) -> int:
        """Starts that completed before and fail after."""
        return sum(1 for b, a in zip(self.before, self.after, strict=False) if b and not a)

    def row(self) -> dict[str, Any]:
        return {
            "name": f"offroute-{self.seed}",
            "teacher": "completed" if self.demo_completed else "failed",
            "before": "".join("✓" if ok else "✗" for ok in self.before),
            "failing_start": self.failing,
            "corrected": self.corrected,
            "after": "".join("✓" if ok else "✗" for ok in self.after),
            "fixed": self.fixed,
            "regressions": self.regressions,
            "decisions": " | ".join(self.verdicts),
        }


def teach_again(seed: int, *, folder: Path, estimate: EstimateOptions = EstimateOptions()) -> TaughtAgain:
    """Demonstrate, learn with sub-goals, run, correct the first failing start once, learn again, run."""
    world = generate_offroute(seed)
    demo = learn.demonstrate(
        THREE_GOALS, world=world, folder=folder, name=f"{world.name}-demo", duration_s=900.0, seed=1
    )
    run = read_segmented(demo.segmented)
    if [s.target for s in run.segments if s.target is not None] != [leg.target for leg in THREE_GOALS]:
        return TaughtAgain(seed, False)
    max_time_s = float(math.ceil(TIME_FACTOR * demo.duration_s / 10.0) * 10.0)
    case = OffRouteCase(world, THREE_GOALS, max_time_s, tuple(str(leg.target) for leg in THREE_GOALS))
    options = learn.LearnOptions(estimate, subgoals=True)
    table = learn.learn([demo.segmented], options=options).table
    poses = [
        p.as_tuple()
        for p in perturbed_starts(world, Pose(*world.start), n=STARTS, rng=np.random.default_rng(seed))
    ]
    rows = run_starts(table, case, starts=poses, folder=folder, label="before")
    before = tuple(bool(r["completed"]) for r in rows)
    if all(before):
        return TaughtAgain(seed, True, before, table_before=table)
    failing = before.index(False)
    teacher_xy = np.asarray(read_run(demo.segmented).pose)[:, :2]
    corr = record_correction(
        table,
        world=world,
        start=Pose(*poses[failing]),
        seed=failing,  # run_starts drives start k with seed k
        failed_log=folder / f"before-{failing}.mcap",
        teacher_xy=teacher_xy,
        max_time_s=max_time_s,
        out=folder / "correction.mcap",
    )
    if corr is None:
        return TaughtAgain(seed, True, before, failing, table_before=table)
    res = learn.learn([demo.segmented, corr], options=options)
    after = tuple(
        bool(r["completed"]) for r in run_starts(res.table, case, starts=poses, folder=folder, label="after")
    )
    return TaughtAgain(
        seed,
        True,
        before,
        failing,
        True,
        after,
        tuple(v.describe() for v in res.verdicts),
        table,
        res.table,
    )


def summary(worlds: list[TaughtAgain]) -> dict[str, Any]:
    failing = [w for w in worlds if w.failing is not None]
    return {
        "worlds": len(worlds),
        "teacher_completed": sum(w.demo_completed for w in worlds),
        "with_a_failing_start": len(failing),
        "corrected": sum(w.corrected for w in failing),
        "fixed": sum(w.fixed for w in failing),
        "regressions": sum(w.regressions for w in failing),
        "worlds_with_a_regression": sum(1 for w in failing if w.regressions),
    }
