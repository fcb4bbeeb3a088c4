"""The paper's experiments (Section V) run with our tools: demonstrate, segment, estimate, execute.

Each function does one experiment in a work folder and returns its numbers and paths as a frozen
dataclass; :mod:`lfdfuse.viz.report` sequences them, draws them and writes the report. Nothing
here draws. Everything is seeded: the same seed gives the same numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import orjson

from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.execute.report import corridor_style
from lfdfuse.execute.run import ExecuteOptions, drive_table
from lfdfuse.log import lfd
from lfdfuse.log.reader import Run as RunLog
from lfdfuse.log.reader import iter_messages, read_run
from lfdfuse.network.table import FusionTable, write_table
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from lfdfuse.sim.loop import side_beam_index
from lfdfuse.sim.robot import Pose
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import World, load_world

#: the paper's three-goal task (Physical Scenario 1): left to red, centre to green, right to blue
THREE_GOALS = (Leg("red", "keep-left"), Leg("green", "keep-center"), Leg("blue", "keep-right"))

#: corridor starts in ``building`` away from the targets (south, east and west corridors)
BUILDING_STARTS = ((10.0, 1.2, 0.0), (38.8, 20.0, -math.pi / 2), (1.2, 25.0, -math.pi / 2))
#: heading north up the middle corridor into the T of the north corridor (left or right)
T_JUNCTION = (20.0, 20.0, math.pi / 2)
#: heading north up the east corridor into the rotated T of the cross corridor (left or straight)
ROTATED_T = (38.8, 6.0, math.pi / 2)


@dataclass(frozen=True)
class Learned:
    """A demonstration and what was learned from it."""

    style: str
    world: str
    demo: Path
    segmented: Path
    table_path: Path
    table: FusionTable
    demo_left_m: float  # mean laser range at +90° over the demonstration
    demo_right_m: float
    demo_style: str
    seconds: float
    demo_pose: np.ndarray  # (N, 3) per scan of the demonstration
    demo_left: np.ndarray  # (N,) laser range at +90° per scan (m)
    demo_right: np.ndarray  # (N,) at −90°


@dataclass(frozen=True)
class Run:
    """One execution of a learned network: its report and its path ``(N, 3)``."""

    label: str
    world: str
    log: Path
    report: dict[str, Any]
    pose: np.ndarray
    left_m: np.ndarray
    right_m: np.ndarray

    @property
    def style(self) -> str:
        return corridor_style(self.left_m, self.right_m)

    def summary(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "world": self.world,
            "log": self.log.name,
            "style": self.style,
            **self.report,
        }


def side_ranges(run: RunLog) -> tuple[np.ndarray, np.ndarray]:
    """Laser ranges at +90° (left) and −90° (right) of every scan of a log (the Fig. 10 measure)."""
    angles = run.geometry.angles
    rng = np.minimum(run.ranges_m, run.geometry.max_range_m)
    return rng[:, side_beam_index(angles, math.pi / 2)], rng[:, side_beam_index(angles, -math.pi / 2)]


def learn(
    work: Path,
    *,
    world: str,
    legs: tuple[Leg, ...],
    name: str,
    seconds: float,
    seed: int,
    estimate: EstimateOptions,
) -> Learned:
    """Simulate a teacher, segment the demo, estimate the table."""
    demo, seg, tab = work / f"{name}.mcap", work / f"{name}.seg.mcap", work / f"{name}.yaml"
    style = ",".join(f"{leg.target}:{leg.style}" if leg.target else leg.style for leg in legs)
    summary = simulate(
        SimulateOptions(
            world=load_world(world), legs=list(legs), teacher_name=style, duration_s=seconds, seed=seed
        ),
        out=demo,
    )
    segment_file(demo, out=seg, measure_lag=False)
    table, _, _ = estimate_run(read_segmented(seg), opts=estimate, name=seg.name)
    write_table(table, tab)
    log = read_run(demo)
    left, right = side_ranges(log)
    pose = log.pose if log.pose is not None else np.zeros((len(log), 3))
    return Learned(
        style,
        world,
        demo,
        seg,
        tab,
        table,
        float(left.mean()),
        float(right.mean()),
        corridor_style(left, right),
        summary.duration_s,
        pose,
        left,
        right,
    )


def execute(
    work: Path,
    table: FusionTable,
    *,
    world: World,
    start: tuple[float, float, float] | None,
    seconds: float,
    name: str,
    label: str,
    seed: int = 0,
) -> Run:
    log = work / f"{name}.mcap"
    res = drive_table(
        ExecuteOptions(
            world=world,
            table=table,
            table_name=name,
            start=None if start is None else Pose(*start),
            max_time_s=seconds,
            seed=seed,
        ),
        out=log,
        command="execute",
    )
    s = res.summary
    return Run(label, world.name, log, res.report, s.poses, s.left_m, s.right_m)


# ------------------------------------------------------------------------------ the measures


def junction_choice(end: np.ndarray, which: str) -> str:
    """Where a run from :data:`T_JUNCTION` or :data:`ROTATED_T` went: left, right, straight or none."""
    x, y = float(end[0]), float(end[1])
    if which == "T":
        if y <= 27.6:
            return "none"
        return "left" if x < 18.0 else "right" if x > 22.0 else "none"
    if x < 36.0 and 13.8 < y < 16.2:
        return "left"
    if x > 37.6 and y > 17.0:
        return "straight"
    return "none"


def passing_sides(pose: np.ndarray, centres: list[tuple[float, float]]) -> list[str]:
    """On which side of the robot each obstacle was when the path crossed the obstacle's x."""
    sides = []
    for ox, oy in centres:
        rel = pose[:, 0] - ox
        for k in np.nonzero(np.sign(rel[:-1]) != np.sign(rel[1:]))[0]:
            hx, hy = math.cos(pose[k, 2]), math.sin(pose[k, 2])
            sides.append("left" if hx * (pose[k, 1] - oy) - hy * (pose[k, 0] - ox) > 0 else "right")
    return sides


def step_of_ticks(log: Path) -> list[str | None]:
    """The active network step of every tick of a run log (``/lfd/step``, one per tick)."""
    return [lfd.decode_step(orjson.loads(data))[0] for *_, data in iter_messages(log, topics=["/lfd/step"])]


def task_order(report: dict[str, Any]) -> list[str]:
    reached = sorted((g for g in report["goals"] if g["reached"]), key=lambda g: g["time_s"])
    return [str(g["target"]) for g in reached]
