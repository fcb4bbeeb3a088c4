"""Simulated sensors: the front laser, the rear sonar ring and the colour camera (DESIGN §3)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Detection, Reading, ScanGeometry
from lfdfuse.world.parse import World
from lfdfuse.world.raycast import RayCaster


@dataclass(frozen=True)
class LaserParams:
    beams: int = 181
    fov_rad: float = math.pi
    max_range_m: float = 8.0
    noise_std_m: float = 0.0

    @property
    def geometry(self) -> ScanGeometry:
        inc = self.fov_rad / (self.beams - 1) if self.beams > 1 else 0.0
        return ScanGeometry(-self.fov_rad / 2, inc, self.beams, self.max_range_m)


@dataclass(frozen=True)
class SonarParams:
    """A rear ring of sonars evenly spread from +90° round the back to −90° (270°)."""

    count: int = 8
    max_range_m: float = 5.0
    noise_std_m: float = 0.0

    @property
    def geometry(self) -> ScanGeometry:
        return ScanGeometry(math.pi / 2, math.pi / (self.count - 1), self.count, self.max_range_m)


@dataclass(frozen=True)
class CameraParams:
    """A colour camera reporting the bearing and range of targets in view and line of sight."""

    fov_rad: float = math.radians(120.0)  # a pan-tilt camera (the paper's PTZ) sees wide
    max_range_m: float = 8.0
    #: a target counts as reached when seen closer than this (centre to centre)
    reach_m: float = 0.75


@dataclass(frozen=True)
class SensorParams:
    laser: LaserParams = field(default_factory=LaserParams)
    sonar: SonarParams = field(default_factory=SonarParams)
    camera: CameraParams = field(default_factory=CameraParams)

    def with_noise(self, std_m: float) -> SensorParams:
        return SensorParams(
            LaserParams(self.laser.beams, self.laser.fov_rad, self.laser.max_range_m, std_m),
            SonarParams(self.sonar.count, self.sonar.max_range_m, std_m),
            self.camera,
        )


def target_reached(range_m: float, camera: CameraParams) -> bool:
    """The goal of ``attract_<target>``: the target seen within the reach distance."""
    return range_m <= camera.reach_m


class Sensors:
    """Senses a world from a pose. Noise, when configured, is drawn from the given generator."""

    def __init__(self, world: World, params: SensorParams, caster: RayCaster | None = None) -> None:
        self.world = world
        self.params = params
        rng = max(params.laser.max_range_m, params.sonar.max_range_m, params.camera.max_range_m)
        self.caster = caster if caster is not None else RayCaster.shared(world.segments, max_range_m=rng)
        self._laser_angles = params.laser.geometry.angles
        self._sonar_angles = params.sonar.geometry.angles

    def _ranges(
        self, pose: Pose, angles: np.ndarray, max_m: float, std: float, rng: np.random.Generator
    ) -> np.ndarray:
        r = np.minimum(self.caster.cast(pose.x, pose.y, angles + pose.theta), max_m)
        if std > 0.0:
            hit = r < max_m
            r = np.where(hit, np.clip(r + rng.normal(0.0, std, r.shape), 0.0, max_m), r)
        return np.asarray(r)

    def sense(self, pose: Pose, rng: np.random.Generator) -> Reading:
        lp, sp = self.params.laser, self.params.sonar
        ranges = self._ranges(pose, self._laser_angles, lp.max_range_m, lp.noise_std_m, rng)
        sonar = self._ranges(pose, self._sonar_angles, sp.max_range_m, sp.noise_std_m, rng)
        return Reading(ranges, sonar, self.detect(pose))

    def detect(self, pose: Pose) -> tuple[Detection, ...]:
        cp = self.params.camera
        found: list[Detection] = []
        for t in self.world.targets:
            dx, dy = t.x - pose.x, t.y - pose.y
            dist = math.hypot(dx, dy)
            bearing = math.atan2(
                math.sin(math.atan2(dy, dx) - pose.theta), math.cos(math.atan2(dy, dx) - pose.theta)
            )
            if dist > cp.max_range_m or abs(bearing) > cp.fov_rad / 2:
                continue
            if not self.caster.visible(pose.x, pose.y, t.x, t.y):
                continue
            found.append(Detection(t.name, bearing, dist))
        return tuple(found)
