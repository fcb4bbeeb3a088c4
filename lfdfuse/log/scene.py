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

#: per entity id and sequence of arrow colours (by identity; the entry keeps the colours, so
#: their ids stay theirs): the colours and :func:`encode_arrow_scene`'s message as a format
_SCENES: dict[tuple[object, ...], tuple[tuple[object, ...], bytes]] = {}


def _arrow(orientation: dict[str, float], shaft_m: float, color: dict[str, float]) -> dict[str, Any]:
    """An arrow primitive of the overlay (at :data:`_ARROW_AT`)."""
    return {
        "pose": {"position": dict(_ARROW_AT), "orientation": orientation},
        "shaft_length": shaft_m,
        "shaft_diameter": 0.03,
        "head_length": 0.1,
        "head_diameter": 0.08,
        "color": color,
    }


def _cut(data: bytes, *marks: bytes) -> list[bytes]:
    """``data`` cut at each of ``marks`` in turn (each found once), as bytes formats (``%`` doubled)."""
    pieces = []
    for mark in marks:
        piece, data = data.split(mark, 1)
        pieces.append(piece.replace(b"%", b"%%"))
    return [*pieces, data.replace(b"%", b"%%")]


def _scene_format(entity_id: str, colors: Sequence[tuple[float, ...]]) -> bytes:
    """:func:`arrow_scene_of`'s message with arrows of ``colors`` as a bytes format: ``%d`` for
    the timestamp's sec and nsec, then ``%s`` for each arrow's orientation z and w and its shaft
    length (orjson's bytes of the message and of an arrow with marked numbers, cut at them)."""
    ent = _entity(0, entity_id, ROBOT_FRAME, arrows=[])
    ent["frame_locked"] = True
    before, between, after = _cut(
        orjson.dumps({"deletions": [], "entities": [ent]}),
        b'"timestamp":' + orjson.dumps(stamp(0)),
        b'"arrows":[]',
    )
    arrows = []
    for color in colors:
        marked = _arrow({"x": 0.0, "y": 0.0, "z": 111.5, "w": 222.5}, 333.5, _color(*color))
        arrows.append(b"%s".join(_cut(orjson.dumps(marked), b"111.5", b"222.5", b"333.5")))
    return b"".join(
        (before, b'"timestamp":{"sec":%d,"nsec":%d}', between, b'"arrows":[', b",".join(arrows), b"]", after)
    )


def encode_arrow_scene(
    t_ns: int, entity_id: str, arrows: Sequence[tuple[float, float, tuple[float, float, float], float]]
) -> bytes:
    """The JSON bytes of :func:`arrow_scene_of` (the same message): its format made once per
    sequence of colours, the numbers of every arrow written by one ``orjson.dumps`` of them all."""
    nums: list[float] = []
    colors: list[tuple[float, float, float]] = []
    hypot, atan2, sin, cos = math.hypot, math.atan2, math.sin, math.cos  # looked up once a message
    for vx, vy, color, scale_m in arrows:
        length = hypot(vx, vy) * scale_m
        if length <= 1e-6:
            continue
        half = atan2(vy, vx) / 2  # quat_z's z and w
        shaft = length - 0.1
        nums += (sin(half), cos(half), 0.01 if 0.01 > shaft else shaft)  # max(shaft, 0.01)
        colors.append(color)
    key = (entity_id, *map(id, colors))
    known = _SCENES.get(key)
    if known is None:
        if len(_SCENES) >= 1024:
            _SCENES.clear()
        known = _SCENES[key] = (tuple(colors), _scene_format(entity_id, colors))
    written = orjson.dumps(nums)[1:-1].split(b",") if nums else []
    return known[1] % (t_ns // 1_000_000_000, t_ns % 1_000_000_000, *written)


def arrow_scene_of(
    t_ns: int, entity_id: str, arrows: Sequence[tuple[float, float, tuple[float, float, float], float]]
) -> dict[str, Any]:
    """:func:`arrow_scene` of arrows as ``(vx, vy, color, scale_m)`` tuples (the same message)."""
    prims = []
    for vx, vy, color, scale_m in arrows:
        length = math.hypot(vx, vy) * scale_m
        if length <= 1e-6:
            continue
        prims.append(_arrow(quat_z(math.atan2(vy, vx)), max(length - 0.1, 0.01), _color(*color)))
    ent = _entity(t_ns, entity_id, ROBOT_FRAME, arrows=prims)
    ent["frame_locked"] = True
    return {"deletions": [], "entities": [ent]}
