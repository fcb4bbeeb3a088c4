"""A behaviour network as a command source: the learned controller, or a network *teacher*.

:class:`NetworkDriver` senses through the same behaviour code as ``segment`` (one scan at a
time), asks the :class:`~lfdfuse.network.runtime.NetworkRuntime` for the fused vector and turns
it into a command with the one vector ↔ command mapping, below a safety reflex. It keeps what
it decided (``last``) so a recorder can log why the robot turned.
"""

from __future__ import annotations

import math
from collections import defaultdict
from typing import Any

import numpy as np

from lfdfuse.behaviors.primitives import BehaviorParams, Observations, compute
from lfdfuse.control.drive import heading_to_command
from lfdfuse.control.safety import SafetyParams, free_heading
from lfdfuse.errors import ConfigError
from lfdfuse.network.runtime import Decision, NetworkRuntime, step_name_of
from lfdfuse.network.table import FusionTable
from lfdfuse.sim.loop import side_beam_index
from lfdfuse.sim.robot import RobotParams
from lfdfuse.sim.sensors import SensorParams, target_reached
from lfdfuse.sim.simulator import Observation
from lfdfuse.world.model import World


def check_table_world(table: FusionTable, world: World) -> None:
    missing = [t for t in table.targets() if t not in world.target_names]
    if missing:
        raise ConfigError(
            f"the table needs target{'s' if len(missing) > 1 else ''} {', '.join(missing)} that world {world.name!r} lacks"
            f" (it has: {', '.join(world.target_names) or 'none'})"
        )


class NetworkDriver:
    """Drives with a fusion table; optional heading noise makes it a network *teacher*."""

    def __init__(
        self,
        *,
        table: FusionTable,
        world: World,
        sensors: SensorParams,
        rng: np.random.Generator,
        heading_noise_rad: float = 0.0,
        robot: RobotParams = RobotParams(),
        safety: SafetyParams | None = SafetyParams(),
    ) -> None:
        check_table_world(table, world)
        self.table = table
        self.runtime = NetworkRuntime(table)
        self.sensors = sensors
        self.params = BehaviorParams(reach_m=sensors.camera.reach_m)
        self.rng = rng
        self.noise = heading_noise_rad
        self.robot = robot
        self.targets = world.target_names
        self.geometry = sensors.laser.geometry
        self.sonar_angles = sensors.sonar.geometry.angles
        self.reached: list[tuple[str, int]] = []
        self.ticks = 0
        self.unseen_ticks = 0
        self.last: Decision | None = None
        self._turn = 0.0
        self.safety = safety
        self.reflex_ticks = 0
        self.last_outputs: Any = None
        self.side: dict[str, list[tuple[float, float]]] = defaultdict(list)
        self._il = side_beam_index(self.geometry.angles, math.pi / 2)
        self._ir = side_beam_index(self.geometry.angles, -math.pi / 2)

    @property
    def done(self) -> bool:
        return self.runtime.complete

    def command(self, observation: Observation) -> tuple[float, float]:
        reading = observation.reading
        obs = Observations.from_detections(
            ranges_m=reading.ranges_m[None, :],
            geometry=self.geometry,
            detections=[reading.detections],
            target_names=self.targets,
            sonar_m=reading.sonar_m[None, :],
            sonar_angles_rad=self.sonar_angles,
            sonar_max_m=self.sensors.sonar.max_range_m,
        )
        outputs = compute(obs, self.table.behaviors, self.params)
        reached = {d.name for d in reading.detections if target_reached(d.range_m, self.sensors.camera)}
        dec = self.runtime.decide(outputs, reached)
        for goal in dec.achieved_now:
            self.reached.append((goal, self.ticks))
        self.last, self.last_outputs = dec, outputs
        self.ticks += 1
        if dec.step is None:
            return 0.0, 0.0
        self.unseen_ticks += dec.unseen
        self.side[step_name_of(dec.path, self.table)].append(
            (float(reading.ranges_m[self._il]), float(reading.ranges_m[self._ir]))
        )
        fx, fy = float(dec.fused[0]), float(dec.fused[1])
        heading = math.atan2(fy, fx) if (fx, fy) != (0.0, 0.0) else 0.0  # no pull at all: straight on
        if abs(heading) > math.radians(120) and self._turn != 0.0:
            # the pull is behind the robot: commit to one turning direction while turning round,
            # instead of dithering as the behind-vector swings from side to side
            heading = math.copysign(abs(heading), self._turn)
        self._turn = math.copysign(1.0, heading) if abs(heading) > math.radians(90) else 0.0
        if self.noise > 0:
            heading += float(self.rng.normal(0.0, self.noise))
        if self.safety is not None:
            safe = free_heading(heading, reading.ranges_m, self.geometry.angles, self.safety)
            self.reflex_ticks += safe != heading
            heading = safe
        v, w = heading_to_command(np.array(heading), self.robot.drive)
        return float(v), float(w)
