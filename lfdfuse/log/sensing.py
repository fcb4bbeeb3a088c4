"""The robot's own channels (DESIGN §5): laser and sonar scans, pose, transform, command, detections.

For each message type the encoder and the decoder sit side by side, so they cannot drift.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from lfdfuse.log.stamps import IDENTITY_POSE, MAP_FRAME, ROBOT_FRAME, from_stamp, quat_z, stamp, yaw_of
from lfdfuse.robot.readings import Detection, ScanGeometry


def laser_scan(
    t_ns: int, ranges_m: np.ndarray, geom: ScanGeometry, *, frame_id: str = ROBOT_FRAME
) -> dict[str, Any]:
    """A ``foxglove.LaserScan``; ranges are rounded to the millimetre."""
    return {
        "timestamp": stamp(t_ns),
        "frame_id": frame_id,
        "pose": IDENTITY_POSE,
        "start_angle": geom.start_rad,
        "end_angle": geom.end_rad,
        # ndarray.round is what np.round calls (without its dispatch)
        "ranges": (ranges_m.round(3) if type(ranges_m) is np.ndarray else np.round(ranges_m, 3)).tolist(),
        "intensities": [],
    }


def pose_in_frame(t_ns: int, x: float, y: float, theta: float) -> dict[str, Any]:
    return {
        "timestamp": stamp(t_ns),
        "frame_id": MAP_FRAME,
        "pose": {"position": {"x": x, "y": y, "z": 0.0}, "orientation": quat_z(theta)},
    }


def frame_transform(t_ns: int, x: float, y: float, theta: float) -> dict[str, Any]:
    return {
        "timestamp": stamp(t_ns),
        "parent_frame_id": MAP_FRAME,
        "child_frame_id": ROBOT_FRAME,
        "translation": {"x": x, "y": y, "z": 0.0},
        "rotation": quat_z(theta),
    }


def twist(t_ns: int, v_mps: float, omega_rps: float) -> dict[str, Any]:
    return {"timestamp": stamp(t_ns), "linear": {"x": v_mps}, "angular": {"z": omega_rps}}


def target_detections(t_ns: int, detections: Sequence[Detection]) -> dict[str, Any]:
    return {
        "timestamp": stamp(t_ns),
        "detections": [
            {"name": d.name, "bearing_rad": round(d.bearing_rad, 6), "range_m": round(d.range_m, 4)}
            for d in detections
        ],
    }


@dataclass(frozen=True)
class ScanMessage:
    """A decoded ``foxglove.LaserScan``: start and end bearing and the ranges (NaN for JSON null)."""

    start_rad: float
    end_rad: float
    ranges_m: list[float]


def decode_scan(msg: dict[str, Any]) -> ScanMessage:
    """Inverse of :func:`laser_scan` (JSON ``null``, how NaN and inf travel, becomes NaN)."""
    ranges = msg["ranges"]
    if any(r is None for r in ranges):
        ranges = [float("nan") if r is None else r for r in ranges]
    return ScanMessage(float(msg["start_angle"]), float(msg["end_angle"]), ranges)


def scan_geometry(scan: ScanMessage, count: int, max_range_m: float) -> ScanGeometry:
    """The beam layout of a decoded scan with ``count`` beams."""
    inc = (scan.end_rad - scan.start_rad) / (count - 1) if count > 1 else 0.0
    return ScanGeometry(scan.start_rad, inc, count, max_range_m)


def decode_pose(msg: dict[str, Any]) -> tuple[float, float, float]:
    """``(x, y, yaw)`` of a ``foxglove.PoseInFrame`` (inverse of :func:`pose_in_frame`)."""
    p = msg["pose"]
    return float(p["position"]["x"]), float(p["position"]["y"]), yaw_of(p["orientation"])


def decode_twist(msg: dict[str, Any]) -> tuple[float, float]:
    """``(v m/s, ω rad/s)`` of an ``lfdfuse.Twist`` (inverse of :func:`twist`)."""
    return float(msg["linear"]["x"]), float(msg["angular"]["z"])


def decode_detections(msg: dict[str, Any]) -> tuple[Detection, ...]:
    """Inverse of :func:`target_detections`."""
    return tuple(Detection(d["name"], d["bearing_rad"], d["range_m"]) for d in msg["detections"])


def stamp_of(msg: dict[str, Any]) -> int:
    """The header stamp of any of our messages, integer nanoseconds."""
    return from_stamp(msg["timestamp"])
