"""A steppable simulator: robot, sensors and clock, and nothing that decides.

``reset(start)`` and ``step(v, ω) -> Observation``, like a gym-style environment without the
framework. A scripted teacher, a behaviour network, a person at the keyboard or a Foxglove
client are only sources of commands (:class:`CommandSource`); :func:`lfdfuse.sim.loop.run`
is the one loop that drives any of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.robot import RobotParams, move
from lfdfuse.sim.sensors import SensorParams, Sensors
from lfdfuse.world.parse import World, check_pose_free


class CommandSource(Protocol):
    """Anything that turns observations into commands ``(v m/s, ω rad/s)``."""

    @property
    def done(self) -> bool: ...

    def command(self, obs: Observation) -> tuple[float, float]: ...


@dataclass
class Simulator:
    """One robot in one world at ``1 / robot.dt_s`` Hz.

    Randomness (sensor noise) is drawn from ``rng``; the same generator may be shared with a
    command source, so a run is reproducible from one seed.
    """

    world: World
    rng: np.random.Generator
    sensors: SensorParams = field(default_factory=SensorParams)
    robot: RobotParams = field(default_factory=RobotParams)

    def __post_init__(self) -> None:
        self._sensors = Sensors(self.world, self.sensors)
        self._dt_ns = int(round(self.robot.dt_s * 1e9))
        self._k = 0
        self._pose = Pose(*self.world.start)
        self.collisions = 0
        self.distance_m = 0.0
        self._blocked = False

    @property
    def dt_ns(self) -> int:
        return self._dt_ns

    @property
    def pose(self) -> Pose:
        return self._pose

    def reset(self, start: Pose | None = None) -> Observation:
        """Place the robot at ``start`` (default: the world's start) and sense."""
        pose = start or Pose(*self.world.start)
        if not all(math.isfinite(v) for v in pose.as_tuple()):
            raise ConfigError(f"start pose must be finite, got {pose.as_tuple()}")
        check_pose_free(self.world, pose.as_tuple(), what="start pose", radius=self.robot.radius_m)
        self._pose, self._k = pose, 0
        self.collisions, self.distance_m, self._blocked = 0, 0.0, False
        return self._observe(blocked=False)

    def step(self, v_mps: float, omega_rps: float) -> Observation:
        """Apply a command for one control period, then sense. A refused move counts once per contact."""
        new, blocked = move(self._pose, v_mps, omega_rps, params=self.robot, caster=self._sensors.caster)
        if blocked and not self._blocked:
            self.collisions += 1
        self._blocked = blocked
        self.distance_m += math.hypot(new.x - self._pose.x, new.y - self._pose.y)
        self._pose = new
        self._k += 1
        return self._observe(blocked=blocked)

    def _observe(self, *, blocked: bool) -> Observation:
        reading = self._sensors.sense(self._pose, self.rng)
        return Observation(self._k, self._k * self._dt_ns, self._pose, reading, blocked)
