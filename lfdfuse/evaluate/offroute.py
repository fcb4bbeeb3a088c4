"""Goals off the style's route (issue 15): a task learned once, run from its teacher's start and perturbed ones.

On buildings whose second target sits in a dead-end spur or an office off the ring, out of
camera view from the route, a scripted teacher demonstrates the task once (:func:`demonstrate`);
the demo is learned with or without sub-goals at decision points (:func:`learn_case`); the
learned table then runs from the teacher's start and from starts perturbed by up to ±0.5 m and
±20° (:func:`run_starts`). The ``offroute`` bench (:mod:`lfdfuse.tools.bench_offroute`) and the
tests compose these.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse import learn
from lfdfuse.errors import LfdError
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.subgoals import refine, track_of
from lfdfuse.execute.run import ExecuteOptions, drive_table
from lfdfuse.execute.starts import perturbed_starts as drawn_starts
from lfdfuse.log.reader import read_run
from lfdfuse.network.table import FusionTable
from lfdfuse.segment.decisions import DecisionParams
from lfdfuse.segment.read import SegmentedRun, read_segmented
from lfdfuse.sim.robot import Pose
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.generate import generate_offroute
from lfdfuse.world.model import World, check_pose_free, load_world


@dataclass(frozen=True)
class OffRouteCase:
    """A building, the task its teacher demonstrates, and how long the learned task may take."""

    world: str | World  # a built-in name, or a world in memory (a generated one)
    legs: tuple[Leg, ...]
    max_time_s: float
    order: tuple[str, ...]

    def load(self) -> World:
        return _world(self.world)


CASES = {
    # the spur is the first opening on the left after red; a right-keeper passes it by
    "ring-spur": OffRouteCase(
        "ring-spur",
        (Leg("red", "keep-center"), Leg("green", "keep-right"), Leg("blue", "keep-right")),
        300.0,
        ("red", "green", "blue"),
    ),
    # green is in the second office on the right; a left-keeper passes both doors by
    "office-room": OffRouteCase(
        "office-room",
        (Leg("red", "keep-left"), Leg("green", "keep-left"), Leg("blue", "keep-left")),
        240.0,
        ("red", "green", "blue"),
    ),
}


def demonstrate(case: OffRouteCase, *, folder: Path, seed: int = 1) -> Path:
    """The teacher's demo of ``case``, segmented; returns the segmented log."""
    world = _world(case.world)
    return learn.demonstrate(
        case.legs,
        world=world,
        folder=folder,
        name=f"{world.name}-demo",
        duration_s=2 * case.max_time_s,
        seed=seed,
    ).segmented


def perturbed_starts(world: World, n: int, *, seed: int) -> list[tuple[float, float, float]]:
    """The world's start and ``n`` starts within ±0.5 m and ±20° of it (free of walls)."""
    rng = np.random.default_rng(seed)
    x0, y0, t0 = world.start
    out = [(x0, y0, t0)]
    while len(out) < n + 1:
        p = (
            x0 + rng.uniform(-0.5, 0.5),
            y0 + rng.uniform(-0.5, 0.5),
            t0 + rng.uniform(-math.radians(20), math.radians(20)),
        )
        try:
            check_pose_free(world, p, what="start", radius=0.3)
        except LfdError:
            continue
        out.append(p)
    return out


def run_starts(
    table: FusionTable,
    case: OffRouteCase,
    *,
    world: str | None = None,
    starts: list[tuple[float, float, float]],
    folder: Path,
    label: str,
) -> list[dict[str, Any]]:
    """Execute ``table`` from every start; one row per start."""
    rows = []
    w = _world(world or case.world)
    for k, start in enumerate(starts):
        res = drive_table(
            ExecuteOptions(world=w, table=table, start=Pose(*start), max_time_s=case.max_time_s, seed=k),
            out=folder / f"{label.replace('/', '-')}-{k}.mcap",
            command="bench",
        )
        rep = res.report
        order = tuple(
            g["target"] for g in sorted((g for g in rep["goals"] if g["reached"]), key=lambda g: g["time_s"])
        )
        rows.append(
            {
                "name": label,
                "world": w.name,
                "start": "teacher" if k == 0 else f"perturbed {k}",
                "completed": bool(rep["completed"]) and order == case.order and rep["collisions"] == 0,
                "reached": ",".join(order) or "-",
                "collisions": rep["collisions"],
                "time_s": rep["duration_s"],
            }
        )
    return rows


def _world(world: str | World) -> World:
    return world if isinstance(world, World) else load_world(world)


def learn_case(seg: Path, *, subgoals: bool, seed: int = 0) -> FusionTable:
    """The table of a segmented demo: the paper's (one step per goal), or with sub-goals."""
    return learn.learn([seg], options=learn.LearnOptions(EstimateOptions(seed=seed), subgoals=subgoals)).table


# ------------------------------------------------------------------ generated off-route worlds

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
) -> GeneratedOutcome:
    """Demonstrate the three-goal task in the generated world of ``seed``, learn it without
    sub-goals and with them (one table per variant of the decision parameters; default: one,
    ``subgoals``), and run every table from ``starts`` perturbed starts (±0.5 m, ±20°, drawn
    from the seed, as ``execute --starts``). A world whose teacher does not complete the task
    has no runs."""
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
    track = track_of(read_run(demo.segmented), run, source=str(demo.segmented))
    tables = {"reactive": plain}
    landmarks: dict[str, tuple[str, ...]] = {}
    for name, params in variants.items():
        tables[name] = refine(plain, run, track, opts=estimate, params=params).table
        landmarks[name] = tuple(
            f"{s.name}: {s.landmark.describe()}"
            for step in tables[name].network.steps
            if step.network is not None
            for s in step.network.steps
            if s.landmark is not None
        )
    poses = [
        p.as_tuple()
        for p in drawn_starts(world, Pose(*world.start), n=starts, rng=np.random.default_rng(seed))
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
