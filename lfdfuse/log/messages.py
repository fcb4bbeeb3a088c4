"""Message builders and the topic → schema table (DESIGN §5).

Builders return plain dicts ready for JSON; each is checked against its schema by a test. Time
stamps are integer nanoseconds from the start of the run, written as ``{sec, nsec}``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from lfdfuse.sim.sensors import Detection, ScanGeometry
from lfdfuse.world.model import World

#: name of the MCAP metadata record that holds provenance
PROVENANCE = "lfdfuse"


@dataclass(frozen=True)
class RawMessage:
    """A message with its channel and schema exactly as stored (for copying through)."""

    topic: str
    schema_name: str
    schema_encoding: str
    schema_data: bytes
    message_encoding: str
    log_time_ns: int
    publish_time_ns: int
    data: bytes


#: topic → schema name (a contract)
TOPICS: dict[str, str] = {
    "/scan": "foxglove.LaserScan",
    "/sonar": "foxglove.LaserScan",
    "/pose": "foxglove.PoseInFrame",
    "/tf": "foxglove.FrameTransform",
    "/cmd_vel": "lfdfuse.Twist",
    "/targets": "lfdfuse.TargetDetections",
    "/world": "foxglove.SceneUpdate",
}

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


_IDENTITY_POSE = {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": quat_z(0.0)}


def laser_scan(
    t_ns: int, ranges_m: np.ndarray, geom: ScanGeometry, *, frame_id: str = ROBOT_FRAME
) -> dict[str, Any]:
    """A ``foxglove.LaserScan``; ranges are rounded to the millimetre."""
    return {
        "timestamp": stamp(t_ns),
        "frame_id": frame_id,
        "pose": _IDENTITY_POSE,
        "start_angle": geom.start_rad,
        "end_angle": geom.end_rad,
        "ranges": np.round(ranges_m, 3).tolist(),
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


def _color(r: float, g: float, b: float, a: float = 1.0) -> dict[str, float]:
    return {"r": r, "g": g, "b": b, "a": a}


def _entity(t_ns: int, entity_id: str, frame_id: str, **prims: list[dict[str, Any]]) -> dict[str, Any]:
    ent: dict[str, Any] = {
        "timestamp": stamp(t_ns),
        "frame_id": frame_id,
        "id": entity_id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": False,
        "metadata": [],
    }
    for kind in ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"):
        ent[kind] = prims.get(kind, [])
    return ent


def _line(
    points: list[tuple[float, float]], color: dict[str, float], thickness: float = 0.05
) -> dict[str, Any]:
    return {
        "type": 0,
        "pose": _IDENTITY_POSE,
        "thickness": thickness,
        "scale_invariant": False,
        "points": [{"x": x, "y": y, "z": 0.0} for x, y in points],
        "color": color,
        "colors": [],
        "indices": [],
    }


def world_scene(t_ns: int, world: World) -> dict[str, Any]:
    """A ``foxglove.SceneUpdate`` drawing walls, obstacles and targets in the map frame."""
    grey = _color(0.2, 0.2, 0.25)
    walls = [_line([tuple(p) for p in w], grey) for w in world.walls]  # type: ignore[misc]
    obstacles = [
        _line(list(ob.polygon().exterior.coords), _color(0.55, 0.35, 0.15), 0.04) for ob in world.obstacles
    ]
    cylinders = [
        {
            "pose": {"position": {"x": t.x, "y": t.y, "z": 0.25}, "orientation": quat_z(0.0)},
            "size": {"x": 2 * t.radius, "y": 2 * t.radius, "z": 0.5},
            "bottom_scale": 1.0,
            "top_scale": 1.0,
            "color": _color(*t.color),
        }
        for t in world.targets
    ]
    texts = [
        {
            "pose": {"position": {"x": t.x, "y": t.y, "z": 0.7}, "orientation": quat_z(0.0)},
            "billboard": True,
            "font_size": 14.0,
            "scale_invariant": True,
            "color": _color(*t.color),
            "text": t.name,
        }
        for t in world.targets
    ]
    return {
        "deletions": [],
        "entities": [
            _entity(t_ns, "walls", MAP_FRAME, lines=walls + obstacles),
            _entity(t_ns, "targets", MAP_FRAME, cylinders=cylinders, texts=texts),
        ],
    }


@dataclass(frozen=True)
class Arrow:
    """An overlay arrow in the robot frame: its vector and colour."""

    vx: float
    vy: float
    color: tuple[float, float, float]
    scale_m: float = 1.0


def arrow_scene(t_ns: int, entity_id: str, arrows: Sequence[Arrow]) -> dict[str, Any]:
    """A ``foxglove.SceneUpdate`` with arrows in the robot frame (behaviour overlay)."""
    prims = []
    for a in arrows:
        length = math.hypot(a.vx, a.vy) * a.scale_m
        if length <= 1e-6:
            continue
        prims.append(
            {
                "pose": {
                    "position": {"x": 0.0, "y": 0.0, "z": 0.3},
                    "orientation": quat_z(math.atan2(a.vy, a.vx)),
                },
                "shaft_length": max(length - 0.1, 0.01),
                "shaft_diameter": 0.03,
                "head_length": 0.1,
                "head_diameter": 0.08,
                "color": _color(*a.color),
            }
        )
    ent = _entity(t_ns, entity_id, ROBOT_FRAME, arrows=prims)
    ent["frame_locked"] = True
    return {"deletions": [], "entities": [ent]}
