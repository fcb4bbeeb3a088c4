"""The network's side of an execute run on the ``/lfd/*`` channels of DESIGN §5.

:class:`LfdRecorder` is a sink of the simulation loop (or of ``drive``'s and ``teleop --table``'s
recorders): every tick the behaviour outputs, BAC, active step and fused vector the network
decided on, an overlay of one arrow per weighted behaviour (in the behaviour's catalogue colour,
as every figure draws it), and on ``/lfd/network`` each request for help (a BAC the table has no
row for, or an unidentifiable row).
"""

from __future__ import annotations

import numpy as np

from lfdfuse.behaviors import catalogue
from lfdfuse.log import lfd
from lfdfuse.log import messages as msg
from lfdfuse.log.writer import LogWriter
from lfdfuse.network.runtime import step_name_of
from lfdfuse.network.stepper import NetworkStepper
from lfdfuse.robot.readings import Observation


class LfdRecorder:
    """Logs the network's decision of every tick on the ``/lfd/*`` channels of DESIGN §5."""

    def __init__(self, log: LogWriter, driver: NetworkStepper) -> None:
        self.log = log
        self.driver = driver
        #: every behaviour's overlay colour, looked up once
        self.colors = {n: catalogue.rgb(n) for n in driver.table.behaviors}
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
        applicable = app.tolist()
        log.write_raw(
            "/lfd/bac", t_ns, lfd.encode_bac(t_ns, dec.bac, [n for j, n in enumerate(names) if applicable[j]])
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
        xy = vec.tolist()  # Python floats: the same numbers as float(vec[j, i])
        arrows = [
            msg.Arrow(
                dec.weights[n] * xy[j][0],
                dec.weights[n] * xy[j][1],
                self.colors[n],  # the behaviour's colour in every figure
                1.5,
            )
            for j, n in enumerate(names)
            if applicable[j] and n in dec.weights
        ]
        arrows.append(msg.Arrow(float(dec.fused[0]), float(dec.fused[1]), (1.0, 1.0, 1.0), 1.5))
        log.write("/lfd/overlay", t_ns, msg.arrow_scene(t_ns, "fusion", arrows))
        ask = self.driver.help_now
        if ask is not None:
            log.write_raw(
                "/lfd/network", t_ns, lfd.encode_help(t_ns, step=ask.step, bac=ask.bac, why=ask.why)
            )
