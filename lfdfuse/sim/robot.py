"""Unicycle kinematics with speed and turn-rate limits, and collision handling (DESIGN §3)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from lfdfuse.control.command import DriveParams
from lfdfuse.robot.pose import Pose
from lfdfuse.world.raycast import RayCaster


@dataclass(frozen=True)
class RobotParams:
    """Pioneer 3DX-like disc robot driven at ``1 / dt_s`` Hz."""

    radius_m: float = 0.25
    dt_s: float = 0.1
    drive: DriveParams = field(default_factory=DriveParams)


def wrap_angle(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def move(pose: Pose, v: float, omega: float, *, params: RobotParams, caster: RayCaster) -> tuple[Pose, bool]:
    """Integrate one control period; returns the new pose and whether a wall blocked the move.

    Commands are clipped to the robot's limits. A translation that would bring the robot disc
    closer than its radius to any segment is refused (the robot turns in place instead), so the
    robot never passes through a wall.
    """
    d = params.drive
    # min/max: np.clip's value, without its cost on a scalar
    v = float(min(max(v, -d.v_max_mps), d.v_max_mps))
    omega = float(min(max(omega, -d.omega_max_rps), d.omega_max_rps))
    dt = params.dt_s
    mid = pose.theta + 0.5 * omega * dt
    theta = wrap_angle(pose.theta + omega * dt)
    nx = pose.x + v * math.cos(mid) * dt
    ny = pose.y + v * math.sin(mid) * dt
    if v != 0.0 and caster.clearance(nx, ny) < params.radius_m:
        return Pose(pose.x, pose.y, theta), True
    return Pose(nx, ny, theta), False
