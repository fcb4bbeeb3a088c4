"""The network's side of an execute run on the ``/lfd/*`` channels of DESIGN §5.

:class:`LfdRecorder` is a sink of the simulation loop (or of ``drive``'s and ``teleop --table``'s
recorders): every tick the behaviour outputs, BAC, active step and fused vector the network
decided on, an overlay of one arrow per weighted behaviour (in the behaviour's catalogue colour,
as every figure draws it), and on ``/lfd/network`` each request for help (a BAC the table has no
row for, or an unidentifiable row).
"""

from __future__ import annotations

import operator

from lfdfuse.behaviors import catalogue
from lfdfuse.log import lfd, lfd_tick
from lfdfuse.log import messages as msg
from lfdfuse.log.writer import LogWriter
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
        #: the last tick's weights (their names in order and the very number objects) and as
        #: ``/lfd/fused`` rounds them
        self._names: tuple[str, ...] = ()
        self._values: tuple[float, ...] = ()
        self._rounded_weights: dict[str, float] = {}

    def _rounded(self, weights: dict[str, float]) -> dict[str, float]:
        """``weights`` rounded as :func:`~lfdfuse.log.lfd.encode_fused` rounds them; the last
        tick's rounding again where the weights are the last tick's: the same names in the same
        order holding the same number objects (a decision copies its row's dict, not its numbers)."""
        names, values = tuple(weights), tuple(weights.values())
        if (
            names == self._names
            and len(values) == len(self._values)
            and all(map(operator.is_, values, self._values))
        ):
            return self._rounded_weights
        self._names, self._values = names, values
        self._rounded_weights = lfd_tick.rounded_weights(weights)
        return self._rounded_weights

    def record(self, obs: Observation, command: tuple[float, float]) -> None:
        driver = self.driver
        dec, out, t_ns = driver.last, driver.last_outputs, obs.t_ns
        if dec is None or out is None:
            return
        names = driver.table.behaviors
        xy = out.vectors[0].round(6).tolist()  # Python floats: the same numbers as float(vec[j, i])
        applicable = out.applicable[0].tolist()
        log = self.log
        log.write_raw(
            "/lfd/behaviors",
            t_ns,
            lfd_tick.encode_behavior_lists(t_ns, names, xy, applicable, out.goal_met[0].tolist()),
        )
        log.write_raw(
            "/lfd/bac", t_ns, lfd.encode_bac(t_ns, dec.bac, [n for j, n in enumerate(names) if applicable[j]])
        )
        step = dec.step
        log.write_raw(
            "/lfd/step",
            t_ns,
            lfd.encode_step(
                t_ns,
                step=driver.step_name(dec.path) if step is not None else None,
                goal=step.goal if step is not None else None,
                bac=dec.bac,
                default_weights=dec.unseen,
                achieved=[g for g, _ in driver.reached],
            ),
        )
        fx, fy = dec.fused.tolist()
        weights, colors = dec.weights, self.colors
        log.write_raw("/lfd/fused", t_ns, lfd_tick.encode_fused_rounded(t_ns, fx, fy, self._rounded(weights)))
        arrows = [
            # the behaviour's colour in every figure
            (weights[n] * xy[j][0], weights[n] * xy[j][1], colors[n], 1.5)
            for j, n in enumerate(names)
            if applicable[j] and n in weights
        ]
        arrows.append((fx, fy, (1.0, 1.0, 1.0), 1.5))
        log.write_raw("/lfd/overlay", t_ns, msg.encode_arrow_scene(t_ns, "fusion", arrows))
        ask = driver.help_now
        if ask is not None:
            log.write_raw(
                "/lfd/network", t_ns, lfd.encode_help(t_ns, step=ask.step, bac=ask.bac, why=ask.why)
            )
