"""Goals off the style's route (issue 15): a learned task run from the teacher's start and perturbed starts.

On buildings whose second target sits in a dead-end spur or an office off the ring, out of
camera view from the route, a scripted teacher demonstrates the task once; the demo is
segmented and estimated, with and without sub-goals at decision points; the learned table then
runs from the teacher's start and from starts perturbed by up to ±0.5 m and ±20°. One row per
(world, method, start): completed in order, collisions, time.

    python -m lfdfuse.tools.bench --suite offroute
"""

from __future__ import annotations

import math
import sys
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.errors import LfdError
from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.estimate.subgoals import estimate_with_subgoals, track_of
from lfdfuse.execute.run import ExecuteOptions, drive_table
from lfdfuse.network.table import FusionTable
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from lfdfuse.sim.robot import Pose
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import World, check_pose_free, load_world


@dataclass(frozen=True)
class OffRouteCase:
    """A building, the task its teacher demonstrates, and how long the learned task may take."""

    world: str
    legs: tuple[Leg, ...]
    max_time_s: float
    order: tuple[str, ...]


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
    demo = folder / f"{case.world}-demo.mcap"
    simulate(
        SimulateOptions(
            world=load_world(case.world),
            legs=list(case.legs),
            teacher_name="task",
            duration_s=2 * case.max_time_s,
            seed=seed,
        ),
        out=demo,
    )
    seg = folder / f"{case.world}-demo.seg.mcap"
    segment_file(demo, out=seg)
    return seg


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
    w = load_world(world or case.world)
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


def learn(seg: Path, *, subgoals: bool, seed: int = 0) -> FusionTable:
    """The table of a segmented demo: the paper's (one step per goal), or with sub-goals."""
    run = read_segmented(seg)
    if subgoals:
        return estimate_with_subgoals(run, track_of(seg, run), opts=EstimateOptions(seed=seed)).table
    table, _, _ = estimate_run(run, opts=EstimateOptions(seed=seed), name=seg.name)
    return table


def run(quick: bool = False) -> list[dict[str, Any]]:
    n = 3 if quick else 10
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for case in CASES.values():
            seg = demonstrate(case, folder=folder)
            starts = perturbed_starts(load_world(case.world), n, seed=15)
            for sub in (False, True):
                table = learn(seg, subgoals=sub)
                label = f"{case.world}/{'subgoals' if sub else 'reactive'}"
                rows += run_starts(table, case, starts=starts, folder=folder, label=label)
                if case.world in TRANSFER:
                    # learned in one building, run in another of the same topology and other sizes
                    other, max_time_s = TRANSFER[case.world]
                    far = perturbed_starts(load_world(other), n, seed=15)
                    longer = replace(case, max_time_s=max_time_s)
                    rows += run_starts(
                        table, longer, world=other, starts=far, folder=folder, label=f"{label}->{other}"
                    )
    return rows


#: transfer runs: learned in the key's world, run in (world, time limit) — a larger building needs longer
TRANSFER = {"ring-spur": ("ring-spur-large", 600.0)}


if __name__ == "__main__":
    for row in run(quick="--quick" in sys.argv):
        print(row)
