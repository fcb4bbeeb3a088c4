"""``execute``: a fusion table drives the simulated robot; the run is logged with why it turned.

Also the network teacher of ``simulate`` (a known table as ground truth, without the ``/lfd``
channels). Besides the raw channels, :class:`LfdRecorder` logs every tick's behaviour outputs,
BAC, active step, fused vector and an overlay of one arrow per weighted behaviour, and on
``/lfd/network`` each request for help (a BAC the table has no row for, or an unidentifiable row).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.execute.report import build_report
from lfdfuse.log import lfd
from lfdfuse.log import messages as msg
from lfdfuse.log.recorder import Recorder, provenance
from lfdfuse.log.writer import LogWriter
from lfdfuse.network.driver import NetworkDriver
from lfdfuse.network.runtime import step_name_of
from lfdfuse.network.table import FusionTable
from lfdfuse.sim.loop import RunSummary, Sink, run
from lfdfuse.sim.robot import Pose, RobotParams
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Observation, Simulator
from lfdfuse.world.model import World

PALETTE = [
    (0.9, 0.3, 0.2),
    (0.2, 0.6, 0.9),
    (0.3, 0.8, 0.3),
    (0.9, 0.7, 0.1),
    (0.7, 0.3, 0.9),
    (0.1, 0.8, 0.8),
    (0.9, 0.4, 0.7),
    (0.6, 0.5, 0.3),
    (0.5, 0.5, 0.9),
    (0.8, 0.8, 0.5),
    (0.4, 0.7, 0.5),
    (0.9, 0.6, 0.4),
    (0.6, 0.6, 0.6),
]


class LfdRecorder:
    """Logs the network's decision of every tick on the ``/lfd/*`` channels of DESIGN §5."""

    def __init__(self, log: LogWriter, driver: NetworkDriver) -> None:
        self.log = log
        self.driver = driver
        for topic, schema in lfd.EXECUTE_TOPICS.items():
            log.add_topic(topic, schema)

    def record(self, obs: Observation, command: tuple[float, float]) -> None:
        dec, out, t_ns = self.driver.last, self.driver.last_outputs, obs.t_ns
        if dec is None or out is None:
            return
        names = self.driver.table.behaviors
        vec = np.round(out.vectors[0], 6)
        app = out.applicable[0]
        log = self.log
        log.write_raw("/lfd/behaviors", t_ns, lfd.encode_behaviors(t_ns, names, vec, app, out.goal_met[0]))
        log.write_raw(
            "/lfd/bac", t_ns, lfd.encode_bac(t_ns, dec.bac, [n for j, n in enumerate(names) if app[j]])
        )
        log.write_raw(
            "/lfd/step",
            t_ns,
            lfd.encode_step(
                t_ns,
                step=step_name_of(dec.path, self.driver.table) if dec.step is not None else None,
                goal=dec.step.goal if dec.step is not None else None,
                bac=dec.bac,
                default_weights=dec.unseen,
                achieved=[g for g, _ in self.driver.reached],
            ),
        )
        log.write_raw(
            "/lfd/fused", t_ns, lfd.encode_fused(t_ns, float(dec.fused[0]), float(dec.fused[1]), dec.weights)
        )
        arrows = [
            msg.Arrow(
                dec.weights[n] * float(vec[j, 0]),
                dec.weights[n] * float(vec[j, 1]),
                PALETTE[j % len(PALETTE)],
                1.5,
            )
            for j, n in enumerate(names)
            if app[j] and n in dec.weights
        ]
        arrows.append(msg.Arrow(float(dec.fused[0]), float(dec.fused[1]), (1.0, 1.0, 1.0), 1.5))
        log.write("/lfd/overlay", t_ns, msg.arrow_scene(t_ns, "fusion", arrows))
        ask = self.driver.help_now
        if ask is not None:
            log.write_raw(
                "/lfd/network", t_ns, lfd.encode_help(t_ns, step=ask.step, bac=ask.bac, why=ask.why)
            )


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


def goal_list(table: FusionTable) -> list[tuple[str, str]]:
    out: list[tuple[str, str]] = []

    def walk(net: Any) -> None:
        for s in net.steps:
            if s.network is not None:
                walk(s.network)
            elif s.goal is not None:
                out.append((s.name, s.goal))

    walk(table.network)
    return out


def drive_table(
    opts: ExecuteOptions, *, out: str | Path, command: str, teacher: bool = False, progress: Any = None
) -> ExecuteResult:
    """Run a fusion table in a world, log the run to ``out`` and build the report."""
    if opts.max_time_s <= 0:
        raise ConfigError("--max-time must be positive")
    rng = np.random.default_rng(opts.seed)
    params = SensorParams().with_noise(opts.sensor_noise_m) if opts.sensor_noise_m > 0 else SensorParams()
    driver = NetworkDriver(
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
    report = build_report(
        summary,
        goals=goal_list(opts.table),
        side=driver.side,
        unseen_ticks=driver.unseen_ticks,
        reflex_ticks=driver.reflex_ticks,
        help=driver.help,
    )
    return ExecuteResult(summary, report)
