"""The execute recorder's ``/lfd`` messages, tick by tick, are the codecs' bytes of what the
network decided (its pieces made once per set of weights, BAC and applicability)."""

from __future__ import annotations

from typing import Any

import numpy as np
import orjson

from lfdfuse.behaviors import catalogue
from lfdfuse.execute.record import LfdRecorder
from lfdfuse.log import lfd
from lfdfuse.log.scene import arrow_scene_of
from lfdfuse.network.stepper import NetworkStepper
from lfdfuse.network.table import parse_table
from lfdfuse.robot.pose import Pose
from lfdfuse.sim.loop import run
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.world.model import load_world

#: two goal steps, rows and defaults: the weights change as the BAC and the step do
TABLE: dict[str, Any] = {
    "format": "lfdfuse/fusion-table@1",
    "behaviors": ["avoid", "attract_red", "wander", "wall_attract", "attract_blue"],
    "default_weights": {"avoid": 0.5, "wander": 0.5},
    "network": {
        "name": "t",
        "steps": [
            {
                "name": "reach-red",
                "goal": {"target": "red"},
                "default_weights": {"wander": 0.6, "attract_red": 1.0, "wall_attract": 0.2},
                "fusion": [
                    {"bac": 0b0111, "weights": {"avoid": 0.2, "attract_red": 0.7, "wander": 0.1}},
                    {"bac": 0b1101, "weights": {"avoid": 0.4, "wander": 0.3, "wall_attract": 0.3}},
                    {"bac": 0b0101, "weights": {"avoid": 0.6, "wander": 0.4}},
                ],
            },
            {"name": "reach-blue", "goal": {"target": "blue"}, "fusion": []},
        ],
    },
}


class _Log:
    def __init__(self) -> None:
        self.ticks: list[tuple[int, list[tuple[str, bytes]]]] = []

    def add_topic(self, topic: str, schema: str) -> None:
        pass

    def write_tick(self, t_ns: int, messages: list[tuple[str, bytes]]) -> None:
        self.ticks.append((t_ns, list(messages)))


def test_each_ticks_fused_and_overlay_are_the_codecs_bytes_of_its_decision() -> None:
    world, sensors = load_world("building"), SensorParams()
    rng = np.random.default_rng(11)
    driver = NetworkStepper(table=parse_table(TABLE), world=world, sensors=sensors, rng=rng)
    log = _Log()
    recorder = LfdRecorder(log, driver)  # type: ignore[arg-type]
    names = driver.table.behaviors
    want: list[tuple[bytes, bytes, bytes]] = []

    class _Codecs:
        """What the codecs write of the decision the recorder is about to log."""

        def record(self, obs: Any, command: tuple[float, float]) -> None:
            dec, out = driver.last, driver.last_outputs
            assert dec is not None and out is not None
            t = obs.t_ns
            fx, fy = dec.fused.tolist()
            xy = out.vectors[0].round(6).tolist()
            app = out.applicable[0].tolist()
            w = dict(dec.weights)
            arrows = [
                (w[n] * xy[j][0], w[n] * xy[j][1], catalogue.rgb(n), 1.5)
                for j, n in enumerate(names)
                if app[j] and n in w
            ]
            arrows.append((fx, fy, (1.0, 1.0, 1.0), 1.5))
            applicable = [n for j, n in enumerate(names) if app[j]]
            want.append(
                (
                    lfd.encode_fused(t, fx, fy, w),
                    orjson.dumps(arrow_scene_of(t, "fusion", arrows)),
                    lfd.encode_bac(t, dec.bac, applicable),
                )
            )

    # red ahead: the BAC changes as it comes into sight, the step as it is reached
    start = Pose(20.0, 5.0, 1.57)
    run(
        Simulator(world, rng, sensors=sensors),
        driver,
        start=start,
        duration_s=40.0,
        sinks=[_Codecs(), recorder],
    )
    assert driver.reached  # red was reached: the second step's weights were used too
    got = [(dict(m)["/lfd/fused"], dict(m)["/lfd/overlay"], dict(m)["/lfd/bac"]) for _, m in log.ticks]
    assert got == want
    # the run met several sets of weights and BACs: the pieces made once were reused across them
    assert len({f for f, _, _ in got}) > 100 and len(recorder._weights) >= 2
    assert len({b[b.index(b"}") :] for _, _, b in got}) >= 2
