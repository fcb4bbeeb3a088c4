"""Time stamps, frames and planar rotations as the messages carry them.

Times are integer nanoseconds (epoch stamps of real logs included); ``{sec, nsec}`` on the wire.
"""

from __future__ import annotations

import math
from typing import Any

MAP_FRAME = "map"
ROBOT_FRAME = "base_link"


def stamp(t_ns: int) -> dict[str, int]:
    return {"sec": t_ns // 1_000_000_000, "nsec": t_ns % 1_000_000_000}


def from_stamp(d: dict[str, Any]) -> int:
    return int(d["sec"]) * 1_000_000_000 + int(d["nsec"])


def quat_z(theta: float) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(theta / 2), "w": math.cos(theta / 2)}


def yaw_of(q: dict[str, float]) -> float:
    return math.atan2(2 * (q["w"] * q["z"] + q["x"] * q["y"]), 1 - 2 * (q["y"] ** 2 + q["z"] ** 2))


IDENTITY_POSE = {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": quat_z(0.0)}
