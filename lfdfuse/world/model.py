"""Worlds by name or path (DESIGN §2): the built-in ones, world YAML files and map_server maps.

The world itself (:class:`World`, :func:`parse_world`) is :mod:`lfdfuse.world.parse`, below both
this loader and :mod:`lfdfuse.world.occupancy`; it is re-exported here, where callers look for it.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from lfdfuse.errors import WorldError
from lfdfuse.files import parse_yaml, read_text
from lfdfuse.world import occupancy
from lfdfuse.world.parse import (
    CIRCLE_SIDES,
    MAX_EXTENT_M,
    MAX_SEGMENTS,
    TARGET_COLORS,
    Obstacle,
    Target,
    World,
    check_pose_free,
    parse_world,
)

__all__ = [
    "CIRCLE_SIDES",
    "DEFAULT_WORLD",
    "MAX_EXTENT_M",
    "MAX_SEGMENTS",
    "TARGET_COLORS",
    "Obstacle",
    "Target",
    "World",
    "builtin_names",
    "check_pose_free",
    "load_world",
    "parse_world",
    "world_descriptions",
]


def builtin_names() -> list[str]:
    folder = resources.files("lfdfuse") / "world" / "builtin"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".yaml"))


DEFAULT_WORLD = "building"


def _exists(path: Path) -> bool:
    try:
        return path.exists()
    except OSError:  # a name too long for a file: not a path to one
        return False


def load_world(name_or_path: str | None) -> World:
    """Load a built-in world by name, or a world YAML or a map_server map YAML by path."""
    spec = DEFAULT_WORLD if name_or_path is None else name_or_path
    if spec in builtin_names():
        text = (resources.files("lfdfuse") / "world" / "builtin" / f"{spec}.yaml").read_text()
        origin = spec
    else:
        path = Path(spec)
        if not spec.strip():
            raise WorldError("the world is empty: give a built-in world name or a YAML path")
        if not (spec.endswith((".yaml", ".yml")) or _exists(path)):
            raise WorldError(
                f"unknown world {spec!r} (built-in worlds: {', '.join(builtin_names())}; or give a YAML path)"
            )
        text = read_text(path, what="world file", error=WorldError)
        origin = str(path)
    data = parse_yaml(text, origin=origin, error=WorldError)
    if occupancy.is_map_yaml(data):
        return occupancy.world_from_map(data, path=Path(origin))
    return parse_world(data, source=text, origin=origin)


def world_descriptions() -> list[tuple[str, str]]:
    return [(n, load_world(n).description) for n in builtin_names()]
