"""Sub-goals that carry: the three-goal task in generated off-route worlds.

In every world of :mod:`tests.support.generated_worlds` (a corridor ring, green at the end of a dead-end
spur, side openings on the way) the scripted teacher demonstrates the paper's three-goal task
once; the demo is learned without sub-goals and with them (one table per variant of the
decision parameters), and every table runs from perturbed starts (±0.5 m, ±20°, as ``execute
--starts`` draws them). :func:`completion` sums a set of worlds up. The ``generated`` bench
(:mod:`tests.bench.generated`) reports the held-apart seeds; landmarks are tuned on the
tuning seeds only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse import learn
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.subgoals import refine, track_of
from lfdfuse.execute.check import CHECK_STARTS
from lfdfuse.execute.starts import perturbed_starts, wilson_interval
from lfdfuse.log.reader import read_run
from lfdfuse.network.table import leaf_steps
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.decisions import DecisionParams
from lfdfuse.segment.read import SegmentedRun, read_segmented
from lfdfuse.sources.tasks import Leg
from tests.support.generated_worlds import generate_offroute
from tests.support.offroute import OffRouteCase, run_starts

#: the paper's three-goal task (``sample_logs/three-goals.task.yaml``), demonstrated in every generated world
THREE_GOALS = (Leg("red", "keep-left"), Leg("green", "keep-center"), Leg("blue", "keep-right"))
#: a learned run may take this many times as long as the teacher took
TIME_FACTOR = 1.5


@dataclass(frozen=True)
class GeneratedOutcome:
    """One generated world: its teacher's demo, and per variant (``reactive``: without
    sub-goals; the others: with sub-goals found by that variant's decision parameters) the
    sub-goal landmarks and the outcome from each start."""

    seed: int
    demo_completed: bool
    demo_s: float
    max_time_s: float
    landmarks: dict[str, tuple[str, ...]]  # per sub-goal variant, each landmark step described
    rows: tuple[dict[str, Any], ...]  # one per (variant, start): run_starts' rows

    def completed(self, variant: str) -> tuple[bool, ...]:
        return tuple(bool(r["completed"]) for r in self.rows if r["name"] == variant)


def run_generated(
    seed: int,
    *,
    folder: Path,
    starts: int = 3,
    variants: dict[str, DecisionParams] | None = None,
    estimate: EstimateOptions = EstimateOptions(),
    check_starts: int | None = CHECK_STARTS,
) -> GeneratedOutcome:
    """Demonstrate the three-goal task in the generated world of ``seed``, learn it without
    sub-goals and with them (one table per variant of the decision parameters; default: one,
    ``subgoals``), and run every table from ``starts`` perturbed starts (±0.5 m, ±20°, drawn
    from the seed, as ``execute --starts``). The sub-goal tables are checked in the world from
    the teacher's start and ``check_starts`` others of the learner's own (None: not checked),
    as ``estimate --subgoals`` does. A world whose teacher does not complete the task has no
    runs."""
    variants = {"subgoals": DecisionParams()} if variants is None else variants
    world = generate_offroute(seed)
    demo = learn.demonstrate(
        THREE_GOALS, world=world, folder=folder, name=f"{world.name}-demo", duration_s=900.0, seed=1
    )
    max_time_s = float(math.ceil(TIME_FACTOR * demo.duration_s / 10.0) * 10.0)
    run = read_segmented(demo.segmented)
    if not _demo_completed(run):
        return GeneratedOutcome(seed, False, demo.duration_s, max_time_s, {}, ())
    case = OffRouteCase(world, THREE_GOALS, max_time_s, tuple(str(leg.target) for leg in THREE_GOALS))
    plain = learn.learn_run(run, options=learn.LearnOptions(estimate), name=demo.segmented.name).table
    raw = read_run(demo.segmented)
    track = track_of(raw, run, source=str(demo.segmented))
    home = learn.home_of(raw, run)
    tables = {"reactive": plain}
    landmarks: dict[str, tuple[str, ...]] = {}
    for name, params in variants.items():
        if home is not None and check_starts is not None:
            opts = learn.LearnOptions(estimate, subgoals=True, decisions=params, check_starts=check_starts)
            tables[name] = learn.subgoals_checked(plain, run, track, home, opts).table
        else:
            tables[name] = refine(plain, run, track, opts=estimate, params=params).table
        landmarks[name] = tuple(
            f"{s.name}: {s.landmark.describe()}" for s in leaf_steps(tables[name]) if s.landmark is not None
        )
    poses = [
        p.as_tuple()
        for p in perturbed_starts(world, Pose(*world.start), n=starts, rng=np.random.default_rng(seed))
    ]
    rows: list[dict[str, Any]] = []
    for label, table in tables.items():
        got = run_starts(table, case, starts=poses, folder=folder, label=label)
        rows += [{**r, "start": f"perturbed {k + 1}", "seed": seed} for k, r in enumerate(got)]
    return GeneratedOutcome(seed, True, demo.duration_s, max_time_s, landmarks, tuple(rows))


def _demo_completed(run: SegmentedRun) -> bool:
    """Every goal of the task reached in the demo (a teacher that did not finish taught nothing whole)."""
    reached = [s.target for s in run.segments if s.target is not None]
    return reached == [leg.target for leg in THREE_GOALS]


@dataclass(frozen=True)
class Completion:
    """How many runs of a variant completed over a set of generated worlds, with the Wilson 95 % interval."""

    variant: str
    completed: int
    runs: int
    worlds: int  # worlds whose teacher completed the task (the others have no runs)

    @property
    def rate(self) -> float | None:
        return None if self.runs == 0 else self.completed / self.runs

    @property
    def ci95(self) -> tuple[float, float]:
        return wilson_interval(self.completed, self.runs)


def completion(outcomes: list[GeneratedOutcome], variant: str) -> Completion:
    """Completion of ``variant`` over ``outcomes`` (worlds whose teacher failed are left out)."""
    done = [c for o in outcomes if o.demo_completed for c in o.completed(variant)]
    return Completion(variant, sum(done), len(done), sum(o.demo_completed for o in outcomes))
