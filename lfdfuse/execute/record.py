"""The network's side of an execute run on the ``/lfd/*`` channels of DESIGN §5.

:class:`LfdRecorder` is a sink of the simulation loop (or of ``drive``'s and ``teleop --table``'s
recorders): every tick the behaviour outputs, BAC, active step and fused vector the network
decided on, an overlay of one arrow per weighted behaviour (in the behaviour's catalogue colour,
as every figure draws it), and on ``/lfd/network`` each request for help (a BAC the table has no
row for, or an unidentifiable row).
"""

from __future__ import annotations

from collections.abc import Mapping

import orjson

from lfdfuse.behaviors import catalogue
from lfdfuse.log import lfd, lfd_tick
from lfdfuse.log import messages as msg
from lfdfuse.log.writer import LogWriter
from lfdfuse.network.stepper import NetworkStepper
from lfdfuse.robot.readings import Observation

#: an arrow of the overlay: where the behaviour's x is in the tick's flat list of vectors (twice
#: its column), its weight and its colour
_Drawn = tuple[int, float, tuple[float, float, float]]


class LfdRecorder:
    """Logs the network's decision of every tick on the ``/lfd/*`` channels of DESIGN §5.

    The bytes are the codecs' (:mod:`lfdfuse.log.lfd`), spliced from pieces made once where a
    message repeats from tick to tick but for its timestamp (:mod:`lfdfuse.log.lfd_tick`).
    """

    def __init__(self, log: LogWriter, driver: NetworkStepper) -> None:
        self.log = log
        self.driver = driver
        #: every behaviour's overlay colour, looked up once
        self.colors = {n: catalogue.rgb(n) for n in driver.table.behaviors}
        for topic, schema in lfd.EXECUTE_TOPICS.items():
            log.add_topic(topic, schema)
        self.behaviors = lfd_tick.BehaviorsEncoder(driver.table.behaviors)
        #: per set of weights (a decision's, the same object every tick its row is used; the
        #: entry keeps it, so its id stays its own): the JSON of them as ``/lfd/fused`` rounds
        #: them, and per BAC the overlay's arrows drawn (see ``_Drawn``)
        self._weights: dict[int, tuple[Mapping[str, float], bytes, dict[int, list[_Drawn]]]] = {}
        #: ``/lfd/bac`` after its timestamp, per BAC and applicability
        self._bacs: dict[int, bytes] = {}
        #: ``/lfd/step`` after its timestamp as of the last tick, and what it was made of
        self._step: tuple[object, bytes] = (None, b"")
        #: the goals achieved so far (``driver.reached``'s, as of its length then)
        self._achieved: tuple[int, list[str]] = (0, [])

    def _of_weights(
        self, weights: Mapping[str, float]
    ) -> tuple[Mapping[str, float], bytes, dict[int, list[_Drawn]]]:
        """The entry of ``weights`` (see ``_weights``), made the first time they are decided with."""
        known = self._weights.get(id(weights))
        if known is None or known[0] is not weights:
            if len(self._weights) >= 1024:
                self._weights.clear()
            rounded = orjson.dumps(lfd_tick.rounded_weights(weights))
            known = self._weights[id(weights)] = (weights, rounded, {})
        return known

    def _achieved_goals(self) -> list[str]:
        reached = self.driver.reached
        n, goals = self._achieved
        if n != len(reached):
            goals = [g for g, _ in reached]
            self._achieved = (len(reached), goals)
        return goals

    def record(self, obs: Observation, command: tuple[float, float]) -> None:
        driver = self.driver
        dec, out, t_ns = driver.last, driver.last_outputs, obs.t_ns
        if dec is None or out is None:
            return
        names = driver.table.behaviors
        # x0, y0, x1, y1, ... as Python floats: the same numbers as float(vec[j, i])
        xy = out.vectors[0].round(6).ravel().tolist()
        applicable = out.applicable[0].tolist()
        head = lfd_tick.stamp_head(t_ns)
        tick = [
            ("/lfd/behaviors", self.behaviors.encode_flat(t_ns, xy, applicable, out.goal_met[0].tolist()))
        ]
        bac = self._bacs.get(dec.bac)  # the BAC is the applicability, bit for bit
        if bac is None:
            if len(self._bacs) >= 4096:
                self._bacs.clear()
            bac = self._bacs[dec.bac] = lfd_tick.tail_of(
                lfd_tick.bac_dict(t_ns, dec.bac, [n for j, n in enumerate(names) if applicable[j]])
            )
        tick.append(("/lfd/bac", head + bac))
        step = dec.step
        achieved = self._achieved_goals()
        made_of = (dec.path if step is not None else None, dec.bac, dec.unseen, achieved)
        if self._step[0] != made_of:
            self._step = (
                made_of,
                lfd_tick.tail_of(
                    lfd_tick.step_dict(
                        t_ns,
                        step=driver.step_name(dec.path) if step is not None else None,
                        goal=step.goal if step is not None else None,
                        bac=dec.bac,
                        default_weights=dec.unseen,
                        achieved=achieved,
                    )
                ),
            )
        tick.append(("/lfd/step", head + self._step[1]))
        fx, fy = dec.fused.tolist()
        weights = dec.weights
        _, rounded, by_bac = self._of_weights(weights)
        x, y = lfd_tick.numbers([fx, fy])
        fused = b"".join((head, b',"x":', x, b',"y":', y, b',"weights":', rounded, b"}"))
        tick.append(("/lfd/fused", fused))
        drawn = by_bac.get(dec.bac)
        if drawn is None:  # the weighted applicable behaviours, each in its colour in every figure
            colors = self.colors
            drawn = by_bac[dec.bac] = [
                (2 * j, weights[n], colors[n]) for j, n in enumerate(names) if applicable[j] and n in weights
            ]
        arrows = [(w * xy[i], w * xy[i + 1], color, 1.5) for i, w, color in drawn]
        arrows.append((fx, fy, (1.0, 1.0, 1.0), 1.5))
        tick.append(("/lfd/overlay", msg.encode_arrow_scene(t_ns, "fusion", arrows)))
        ask = driver.help_now
        if ask is not None:
            tick.append(("/lfd/network", lfd.encode_help(t_ns, step=ask.step, bac=ask.bac, why=ask.why)))
        self.log.write_tick(t_ns, tick)
