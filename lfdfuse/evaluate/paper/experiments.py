"""One experiment's pieces: demonstrate and learn (:mod:`lfdfuse.learn`), run a learned network.

Each function works in a folder and returns a frozen record (:mod:`~lfdfuse.evaluate.paper.records`).
Everything is seeded: the same seed gives the same numbers.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from lfdfuse import learn
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.evaluate.paper.records import Learned, PaperRun
from lfdfuse.execute.report import corridor_style
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.log import lfd
from lfdfuse.log.reader import Run as RunLog
from lfdfuse.log.reader import iter_messages, read_run
from lfdfuse.network.table import FusionTable, write_table
from lfdfuse.robot.pose import Pose
from lfdfuse.sim.loop import side_beam_index
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


def side_ranges(run: RunLog) -> tuple[np.ndarray, np.ndarray]:
    """Laser ranges at +90° (left) and −90° (right) of every scan of a log (the Fig. 10 measure)."""
    angles = run.geometry.angles
    rng = np.minimum(run.ranges_m, run.geometry.max_range_m)
    return rng[:, side_beam_index(angles, math.pi / 2)], rng[:, side_beam_index(angles, -math.pi / 2)]


def demonstrate_and_learn(
    work: Path,
    *,
    world: str,
    legs: tuple[Leg, ...],
    name: str,
    seconds: float,
    seed: int,
    estimate: EstimateOptions,
) -> Learned:
    """A teacher demonstrates ``legs`` in ``world``; the demo is segmented and learned."""
    style = ",".join(f"{leg.target}:{leg.style}" if leg.target else leg.style for leg in legs)
    demo = learn.demonstrate(
        legs,
        world=load_world(world),
        folder=work,
        name=name,
        duration_s=seconds,
        seed=seed,
        teacher_name=style,
        measure_lag=False,
    )
    table = learn.learn([demo.segmented], options=learn.LearnOptions(estimate)).table
    write_table(table, work / f"{name}.yaml")
    log = read_run(demo.raw)
    left, right = side_ranges(log)
    pose = log.pose if log.pose is not None else np.zeros((len(log), 3))
    return Learned(
        style,
        world,
        demo.raw,
        demo.segmented,
        work / f"{name}.yaml",
        table,
        float(left.mean()),
        float(right.mean()),
        corridor_style(left, right),
        demo.duration_s,
        pose,
        left,
        right,
    )


def relearn_table(segmented: Path, *, estimate: EstimateOptions, out: Path) -> FusionTable:
    """A segmented demonstration learned with ``estimate``, the table written to ``out``."""
    table = learn.learn([segmented], options=learn.LearnOptions(estimate)).table
    write_table(table, out)
    return table


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
) -> PaperRun:
    """Run ``table`` in ``world`` from ``start`` (None: the world's) for ``seconds``; ``work/name.mcap``."""
    log = work / f"{name}.mcap"
    res = run_table(
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
    return PaperRun(
        label, world.name, log, res.report, s.poses, s.left_m, s.right_m, corridor_style(s.left_m, s.right_m)
    )


def step_of_ticks(log: Path) -> list[str | None]:
    """The active network step of every tick of a run log (``/lfd/step``, one per tick)."""
    return [lfd.NetworkStep.decode(data).step for *_, data in iter_messages(log, topics=["/lfd/step"])]
