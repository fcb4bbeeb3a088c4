"""Teach again: where a table learned with sub-goals fails, one correction and a re-estimate.

In the generated off-route world of a seed (:mod:`tests.support.generated_worlds`) the scripted
teacher demonstrates the three-goal task once; the demo is learned with sub-goals, checked in its
world (``estimate --subgoals``), and the table runs from :data:`STARTS` perturbed starts
(:func:`screen`). From the first start that fails, a scripted person corrects it once
(:mod:`tests.support.corrections`: the teacher's path where the robot left it); the demo and the
correction are estimated together with sub-goals (``estimate demo.seg.mcap corr.seg.mcap
--subgoals``) and the new table runs from the same starts (:func:`teach_again_screened`).

Screening does not depend on how corrections are learned, so its result is kept in the world's
folder (``screen.pickle``: the demo's table and the runs before) and a second pass over the same
folder learns the correction again without screening again. :func:`teach_again` is one world;
the ``corrections`` bench many. Every phase's wall time is kept (``times``).
"""

from __future__ import annotations

import math
import pickle
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse import learn
from lfdfuse.errors import ConfigError
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.execute.starts import perturbed_starts
from lfdfuse.log.reader import read_run
from lfdfuse.network.table import FusionTable
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.read import read_segmented
from tests.support.corrections import TAKEOVERS, record_correction
from tests.support.generated import THREE_GOALS, TIME_FACTOR
from tests.support.generated_worlds import generate_offroute
from tests.support.offroute import OffRouteCase, run_starts

#: the starts every table runs from: the failing one and (at least) three others
STARTS = 4
SCREEN_FILE = "screen.pickle"


@dataclass(frozen=True)
class TaughtAgain:
    """One world: the table's runs before, the correction (from the first failing start), after."""

    seed: int
    demo_completed: bool
    before: tuple[bool, ...] = ()
    failing: int | None = None  # index of the start corrected
    #: a correction was recorded (the failing run left the teacher's path or hit a wall)
    corrected: bool = False
    after: tuple[bool, ...] = ()
    verdicts: tuple[str, ...] = ()
    table_before: FusionTable | None = field(default=None, compare=False)
    table_after: FusionTable | None = field(default=None, compare=False)
    times: dict[str, float] = field(default_factory=dict, compare=False)  # wall s per phase

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
            "wall_s": {k: round(v, 1) for k, v in self.times.items()},
        }


@dataclass(frozen=True)
class Screened:
    """A world screened: its demo, the table learned from it and the runs before."""

    seed: int
    demo_segmented: Path
    demo_completed: bool
    max_time_s: float = 0.0
    poses: tuple[tuple[float, float, float], ...] = ()
    table: FusionTable | None = None
    before: tuple[bool, ...] = ()
    times: dict[str, float] = field(default_factory=dict)


class _Clock:
    def __init__(self) -> None:
        self.times: dict[str, float] = {}
        self._t = time.perf_counter()

    def lap(self, name: str) -> None:
        now = time.perf_counter()
        self.times[name] = self.times.get(name, 0.0) + now - self._t
        self._t = now


def _case(seed: int, max_time_s: float) -> OffRouteCase:
    return OffRouteCase(
        generate_offroute(seed), THREE_GOALS, max_time_s, tuple(str(leg.target) for leg in THREE_GOALS)
    )


def screen(seed: int, *, folder: Path, estimate: EstimateOptions = EstimateOptions()) -> Screened:
    """Demonstrate, learn with sub-goals and run from every start (kept in ``folder``: a second
    call reads it back)."""
    kept = folder / SCREEN_FILE
    if kept.exists():
        with kept.open("rb") as f:
            done: Screened = pickle.load(f)
        return done
    clock = _Clock()
    world = generate_offroute(seed)
    demo = learn.demonstrate(
        THREE_GOALS, world=world, folder=folder, name=f"{world.name}-demo", duration_s=900.0, seed=1
    )
    clock.lap("demonstrate+segment")
    run = read_segmented(demo.segmented)
    out = Screened(seed, demo.segmented, False)
    if [s.target for s in run.segments if s.target is not None] == [leg.target for leg in THREE_GOALS]:
        max_time_s = float(math.ceil(TIME_FACTOR * demo.duration_s / 10.0) * 10.0)
        options = learn.LearnOptions(estimate, subgoals=True)
        table = learn.learn([demo.segmented], options=options).table
        clock.lap("estimate --subgoals")
        poses = tuple(
            p.as_tuple()
            for p in perturbed_starts(world, Pose(*world.start), n=STARTS, rng=np.random.default_rng(seed))
        )
        rows = run_starts(table, _case(seed, max_time_s), starts=list(poses), folder=folder, label="before")
        clock.lap("execute before")
        before = tuple(bool(r["completed"]) for r in rows)
        out = Screened(seed, demo.segmented, True, max_time_s, poses, table, before)
    out = replace(out, times=clock.times)
    with kept.open("wb") as f:
        pickle.dump(out, f)
    return out


def teach_again_screened(
    s: Screened, *, folder: Path, estimate: EstimateOptions = EstimateOptions(), takeovers: int = TAKEOVERS
) -> TaughtAgain:
    """From a screened world: correct the first failing start once (a person who takes over up
    to ``takeovers`` times in that run), learn again, run again."""
    if not s.demo_completed or s.table is None:
        return TaughtAgain(s.seed, False, times=s.times)
    if all(s.before):
        return TaughtAgain(s.seed, True, s.before, table_before=s.table, times=s.times)
    clock = _Clock()
    table, poses = s.table, s.poses
    failing = s.before.index(False)
    teacher_xy = np.asarray(read_run(s.demo_segmented).pose)[:, :2]
    goals_at = [g.stop - 1 for g in read_segmented(s.demo_segmented).segments if g.target is not None]
    corr = record_correction(
        table,
        world=generate_offroute(s.seed),
        start=Pose(*poses[failing]),
        seed=failing,  # run_starts drives start k with seed k
        failed_log=folder / f"before-{failing}.mcap",
        teacher_xy=teacher_xy,
        goals_at=goals_at,
        max_time_s=s.max_time_s,
        out=folder / "correction.mcap",
        takeovers=takeovers,
    )
    clock.lap("correct+segment")
    if corr is None:
        return TaughtAgain(
            s.seed, True, s.before, failing, table_before=table, times={**s.times, **clock.times}
        )
    try:
        res = learn.learn([s.demo_segmented, corr], options=learn.LearnOptions(estimate, subgoals=True))
    except ConfigError as e:  # the estimate refuses the correction: not fixed, no runs after
        clock.lap("estimate demo+correction")
        return TaughtAgain(
            s.seed,
            True,
            s.before,
            failing,
            True,
            verdicts=(f"refused: {e}",),
            table_before=table,
            times={**s.times, **clock.times},
        )
    clock.lap("estimate demo+correction")
    after = tuple(
        bool(r["completed"])
        for r in run_starts(
            res.table, _case(s.seed, s.max_time_s), starts=list(poses), folder=folder, label="after"
        )
    )
    clock.lap("execute after")
    return TaughtAgain(
        s.seed,
        True,
        s.before,
        failing,
        True,
        after,
        tuple(v.describe() for v in res.verdicts) + (() if res.lesson is None else (res.lesson.describe(),)),
        table,
        res.table,
        {**s.times, **clock.times},
    )


def teach_again(
    seed: int, *, folder: Path, estimate: EstimateOptions = EstimateOptions(), takeovers: int = TAKEOVERS
) -> TaughtAgain:
    """Demonstrate, learn with sub-goals, run, correct the first failing start once, learn again, run."""
    folder.mkdir(parents=True, exist_ok=True)
    return teach_again_screened(
        screen(seed, folder=folder, estimate=estimate), folder=folder, estimate=estimate, takeovers=takeovers
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
