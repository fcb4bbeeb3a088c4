"""Scene updates for viewers: the world (walls, obstacles, targets) and the fusion overlay arrows."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import orjson

from lfdfuse.log.stamps import IDENTITY_POSE, MAP_FRAME, ROBOT_FRAME, quat_z, stamp
from lfdfuse.world.parse import World


def _color(r: float, g: float, b: float, a: float = 1.0) -> dict[str, float]:
    return {"r": r, "g": g, "b": b, "a": a}


def _entity(
    t_ns: int,
    entity_id: str,
    frame_id: str,
    *,
    arrows: list[dict[str, Any]] | None = None,
    cylinders: list[dict[str, Any]] | None = None,
    lines: list[dict[str, Any]] | None = None,
    texts: list[dict[str, Any]] | None = None,
) -> dict[str, Any]:
    return {
        "timestamp": stamp(t_ns),
        "frame_id": frame_id,
        "id": entity_id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": False,
        "metadata": [],
        "arrows": [] if arrows is None else arrows,
        "cubes": [],
        "spheres": [],
        "cylinders": [] if cylinders is None else cylinders,
        "lines": [] if lines is None else lines,
        "triangles": [],
        "texts": [] if texts is None else texts,
        "models": [],
    }


def _line(
    points: list[tuple[float, float]], color: dict[str, float], thickness: float = 0.05
) -> dict[str, Any]:
    return {
        "type": 0,
        "pose": IDENTITY_POSE,
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
    return arrow_scene_of(t_ns, entity_id, [(a.vx, a.vy, a.color, a.scale_m) for a in arrows])


#: every arrow's position in the robot frame
_ARROW_AT = {"x": 0.0, "y": 0.0, "z": 0.3}

#: the colour objects of :func:`encode_arrow_scene`, one per colour (its messages never escape)
_COLORS: dict[tuple[float, float, float], dict[str, float]] = {}


def encode_arrow_scene(
    t_ns: int, entity_id: str, arrows: Sequence[tuple[float, float, tuple[float, float, float], float]]
) -> bytes:
    """The JSON bytes of :func:`arrow_scene_of` (the same message): its position and colour
    objects shared between arrows and messages, as the message is serialised at once."""
    prims = []
    for vx, vy, color, scale_m in arrows:
        length = math.hypot(vx, vy) * scale_m
        if length <= 1e-6:
            continue
        c = _COLORS.get(color)
        if c is None:
            if len(_COLORS) >= 256:
                _COLORS.clear()
            c = _COLORS[color] = _color(*color)
        prims.append(
            {
                "pose": {"position": _ARROW_AT, "orientation": quat_z(math.atan2(vy, vx))},
                "shaft_length": max(length - 0.1, 0.01),
                "shaft_diameter": 0.03,
                "head_length": 0.1,
                "head_diameter": 0.08,
                "color": c,
            }
        )
    ent = _entity(t_ns, entity_id, ROBOT_FRAME, arrows=prims)
    ent["frame_locked"] = True
    return orjson.dumps({"deletions": [], "entities": [ent]})


def arrow_scene_of(
    t_ns: int, entity_id: str, arrows: Sequence[tuple[float, float, tuple[float, float, float], float]]
) -> dict[str, Any]:
    """:func:`arrow_scene` of arrows as ``(vx, vy, color, scale_m)`` tuples (the same message)."""
    prims = []
    for vx, vy, color, scale_m in arrows:
        length = math.hypot(vx, vy) * scale_m
        if length <= 1e-6:
            continue
        prims.append(
            {
                "pose": {"position": dict(_ARROW_AT), "orientation": quat_z(math.atan2(vy, vx))},
                "shaft_length": max(length - 0.1, 0.01),
                "shaft_diameter": 0.03,
                "head_length": 0.1,
                "head_diameter": 0.08,
                "color": _color(*color),
            }
        )
    ent = _entity(t_ns, entity_id, ROBOT_FRAME, arrows=prims)
    ent["frame_locked"] = True
    return {"deletions": [], "entities": [ent]}
