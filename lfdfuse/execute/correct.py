"""``teleop --table``: the learned network drives and a person corrects it (DESIGN §10).

The network is execute's own :class:`~lfdfuse.network.stepper.NetworkStepper`, handed to the
teleop session as its ``network`` command source: the session asks it every period and decides
who drives (:class:`~lfdfuse.sources.teleop.session.TeleopSession`), the one loop of
:mod:`lfdfuse.sim.loop` runs, and :class:`~lfdfuse.execute.record.LfdRecorder` logs the network's
proposal (``/lfd/step``, ``/lfd/fused``, help on ``/lfd/network``) every tick, also while the
person drives. Until the first input the run is tick for tick ``execute``'s of the same table,
seed and start; ``/lfd/authority`` tells the learner's ticks from the teacher's.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.execute.record import LfdRecorder
from lfdfuse.execute.report import network_report
from lfdfuse.log.writer import LogWriter
from lfdfuse.network.stepper import NetworkStepper
from lfdfuse.network.table import FusionTable
from lfdfuse.sim.loop import Sink
from lfdfuse.sources.teleop.session import TeleopOptions, TeleopSession, TeleopSummary, teleop


def correction_driver(opts: TeleopOptions, table: FusionTable) -> NetworkStepper:
    """The network of a correction run: ``execute``'s driver, as ``execute`` builds it for the
    same world, sensors, robot and seed (no heading noise: the learner drives as it would alone)."""
    return NetworkStepper(
        table=table,
        world=opts.world,
        sensors=opts.sensors,
        rng=np.random.default_rng(opts.seed),
        robot=opts.robot,
    )


@dataclass(frozen=True)
class CorrectionResult:
    """A correction run: the teleop summary and execute's report of the network's task (its
    collisions are those that began while the network drove), with a ``correction`` entry (ticks
    the person drove, takeovers, collisions while the person drove)."""

    teleop: TeleopSummary
    report: dict[str, Any]


def correct(
    opts: TeleopOptions,
    *,
    session: TeleopSession,
    driver: NetworkStepper,
    table_name: str,
    out: str | Path,
    sinks: tuple[Sink, ...] = (),
) -> CorrectionResult:
    """Run ``session`` (made with ``network=driver``) and record ``out``: teleop's channels,
    ``/lfd/authority`` and execute's ``/lfd/*``; provenance names the table."""
    if session.network is not driver:
        raise ValueError("the session must be made with this driver as its network")

    def lfd_recorder(log: LogWriter) -> Sink:
        return LfdRecorder(log, driver)

    summary = teleop(
        opts,
        session=session,
        out=out,
        sinks=sinks,
        log_sinks=[lfd_recorder],
        metadata={"table": table_name, "behaviors": ",".join(driver.table.behaviors), "corrects": "network"},
    )
    dt = opts.robot.dt_s
    # the task is the network's: complete when its last goal is achieved, goals in its order
    task = replace(
        summary.run,
        completed=driver.done,
        reached=tuple((name, k * dt) for name, k in driver.reached),
        collisions=session.network_collisions,
    )
    report = network_report(task, driver)
    report["correction"] = {
        "person_ticks": session.person_ticks,
        "network_ticks": session.network_ticks,
        "takeovers": session.takeovers,
        "person_collisions": session.person_collisions,
    }
    return CorrectionResult(summary, report)
