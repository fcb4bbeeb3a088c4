"""Goals off the style's route: a task learned once, run from its teacher's start and perturbed ones.

On buildings whose second target sits in a dead-end spur or an office off the ring, out of
camera view from the route, a scripted teacher demonstrates the task once (:func:`demonstrate`);
the demo is learned with or without sub-goals at decision points (:func:`learn_case`); the
learned table then runs from the teacher's start and from starts perturbed by up to ±0.5 m and
±20° (:func:`run_starts`). The ``offroute`` bench (:mod:`tests.bench.offroute`) and the
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
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.network.table import FusionTable
from lfdfuse.robot.pose import Pose
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import World, check_pose_free, load_world


@dataclass(frozen=True)
class OffRouteCase:
    """A building, the task its teacher demonstrates, and how long the learned task may take."""

    world: str | World  # a built-in name, or a world in memory (a generated one)
    legs: tuple[Leg, ...]
    max_time_s: float
    order: tuple[str, ...]

    def load(self) -> World:
        return self.world if isinstance(self.world, World) else load_world(self.world)


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
    world = case.load()
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
    w = load_world(world) if world is not None else case.load()
    for k, start in enumerate(starts):
        res = run_table(
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
                # where a run that did not complete was when the time ran out: the step it last
                # entered (a landmark never met, or a goal step that never got there)
                "ended_in": "" if rep["completed"] or not rep["steps"] else rep["steps"][-1]["name"],
            }
        )
    return rows


def learn_case(seg: Path, *, subgoals: bool, seed: int = 0) -> FusionTable:
    """The table of a segmented demo: the paper's (one step per goal), or with sub-goals."""
    return learn.learn([seg], options=learn.LearnOptions(EstimateOptions(seed=seed), subgoals=subgoals)).table
