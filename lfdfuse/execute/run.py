"""``execute``: a fusion table drives the simulated robot; the run is logged with why it turned.

Also the network teacher of ``simulate`` (a known table as ground truth, without the ``/lfd``
channels). Besides the raw channels, :class:`~lfdfuse.execute.record.LfdRecorder` logs why the
network turned; :func:`~lfdfuse.execute.report.network_report` judges the run.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.execute.record import LfdRecorder
from lfdfuse.execute.report import network_report
from lfdfuse.log.recorder import Recorder, provenance
from lfdfuse.log.writer import LogWriter
from lfdfuse.network.stepper import NetworkStepper
from lfdfuse.network.table import FusionTable
from lfdfuse.robot.pose import Pose
from lfdfuse.sim.loop import RunSummary, Sink, run
from lfdfuse.sim.robot import RobotParams
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.world.parse import World


@dataclass(frozen=True)
class ExecuteOptions:
    world: World
    table: FusionTable
    table_name: str = "fusion.yaml"
    start: Pose | None = None
    max_time_s: float = 300.0
    seed: int = 0
    heading_noise_rad: float = 0.0
    sensor_noise_m: float = 0.0
    stop_on_collision: bool = False
    robot: RobotParams = field(default_factory=RobotParams)


@dataclass(frozen=True)
class ExecuteResult:
    summary: RunSummary
    report: dict[str, Any]


def run_table(
    opts: ExecuteOptions, *, out: str | Path, command: str, teacher: bool = False, progress: Any = None
) -> ExecuteResult:
    """Run a fusion table in a world, log the run to ``out`` and build the report."""
    if opts.max_time_s <= 0:
        raise ConfigError("--max-time must be positive")
    rng = np.random.default_rng(opts.seed)
    params = SensorParams().with_noise(opts.sensor_noise_m) if opts.sensor_noise_m > 0 else SensorParams()
    driver = NetworkStepper(
        table=opts.table,
        world=opts.world,
        sensors=params,
        rng=rng,
        heading_noise_rad=opts.heading_noise_rad,
        robot=opts.robot,
    )
    start = opts.start or Pose(*opts.world.start)
    meta = provenance(
        command=command,
        seed=opts.seed,
        world=opts.world,
        sensors=params,
        teacher=opts.table_name if teacher else "",
        table=opts.table_name,
        behaviors=",".join(opts.table.behaviors),
        duration_s=repr(opts.max_time_s),
        start=",".join(repr(v) for v in start.as_tuple()),
        heading_noise_rad=repr(opts.heading_noise_rad),
    )
    sim = Simulator(opts.world, rng, params, opts.robot)
    with LogWriter(out, metadata=meta) as log:
        sinks: list[Sink] = [Recorder(log, world=opts.world, sensors=params)]
        if not teacher:
            sinks.append(LfdRecorder(log, driver))
        summary = run(
            sim,
            driver,
            start=start,
            duration_s=opts.max_time_s,
            sinks=sinks,
            stop_on_collision=opts.stop_on_collision,
            progress=progress,
            out=str(out),
        )
    return ExecuteResult(summary, network_report(summary, driver))
