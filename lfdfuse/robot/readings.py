"""What the robot senses, in its base frame: the scan layout, a reading, an observation.

Whoever senses — the simulator, a log read back, a robot on the wire — hands the behaviours a
:class:`Reading` (laser ranges, rear sonars, camera :class:`Detection` s) laid out by a
:class:`ScanGeometry`, inside an :class:`Observation` at one tick.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from lfdfuse.robot.pose import Pose


@dataclass(frozen=True)
class ScanGeometry:
    """Beam layout of a planar scanner: beam ``i`` is at ``start_rad + i·increment_rad``."""

    start_rad: float
    increment_rad: float
    count: int
    max_range_m: float

    @cached_property
    def angles(self) -> np.ndarray:
        """``(B,)`` beam bearings (rad), computed once per layout and read-only."""
        a = self.start_rad + self.increment_rad * np.arange(self.count)
        a.flags.writeable = False
        return a

    @property
    def end_rad(self) -> float:
        return self.start_rad + self.increment_rad * (self.count - 1)


@dataclass(frozen=True)
class Detection:
    """One target seen by the camera: robot-frame bearing (rad) and range (m)."""

    name: str
    bearing_rad: float
    range_m: float


@dataclass(frozen=True)
class Reading:
    """Everything the robot senses at one instant."""

    ranges_m: np.ndarray  # (B,) laser, no return = max range
    sonar_m: np.ndarray  # (8,) rear sonars, no return = max range
    detections: tuple[Detection, ...]


@dataclass(frozen=True)
class Observation:
    """What the robot senses at tick ``k`` (time ``t_ns`` from the start of the run).

    ``pose`` is the true pose (the simulator knows it; it is logged as ``/pose``), or
    odometry's on a real robot; ``blocked`` whether the move that led here was refused by a wall.
    """

    k: int
    t_ns: int
    pose: Pose
    reading: Reading
    blocked: bool = False
