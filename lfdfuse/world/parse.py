"""World files (DESIGN §2): walls, obstacles, targets and a start pose, in metres and radians.

A world is parsed once, at the edge, into a frozen :class:`World` (finding and loading a world
file by name or path is :mod:`lfdfuse.world.model`, above this module and the occupancy maps). Geometry is kept as shapely
objects for exact queries and as a flat ``(S, 4)`` array of segments ``[ax, ay, bx, by]`` for
the vectorised raycaster.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from shapely.geometry import LineString, MultiLineString, Point, Polygon

from lfdfuse.errors import WorldError
from lfdfuse.validate import number, validate

#: Circles become regular polygons with this many sides for the laser and collisions.
CIRCLE_SIDES = 32

_WORLD_KEYS = {"name", "walls", "obstacles", "targets", "start", "description"}
_TARGET_KEYS = {"name", "position", "radius", "color"}

#: Colours (r, g, b) of well-known target names, for viewers; others are grey.
TARGET_COLORS: dict[str, tuple[float, float, float]] = {
    "red": (0.9, 0.1, 0.1),
    "green": (0.1, 0.75, 0.2),
    "blue": (0.15, 0.3, 0.95),
    "yellow": (0.95, 0.85, 0.1),
    "orange": (1.0, 0.55, 0.0),
    "magenta": (0.9, 0.1, 0.9),
}


@dataclass(frozen=True)
class Target:
    """A coloured cylinder the camera can see. It does not block the laser or the robot."""

    name: str
    x: float
    y: float
    radius: float = 0.25

    @property
    def color(self) -> tuple[float, float, float]:
        return TARGET_COLORS.get(self.name, (0.6, 0.6, 0.6))


@dataclass(frozen=True)
class Obstacle:
    """A circle ``(x, y, radius)`` or a polygon given by its vertices."""

    kind: str  # "circle" or "polygon"
    circle: tuple[float, float, float] | None = None
    points: tuple[tuple[float, float], ...] = ()

    def polygon(self) -> Polygon:
        if self.circle is not None:
            x, y, r = self.circle
            ang = np.arange(CIRCLE_SIDES) * (2 * math.pi / CIRCLE_SIDES)
            return Polygon(np.column_stack([x + r * np.cos(ang), y + r * np.sin(ang)]))
        return Polygon(self.points)


@dataclass(frozen=True)
class World:
    """A parsed, validated world. ``segments`` is ``(S, 4)`` float64 ``[ax, ay, bx, by]``."""

    name: str
    walls: tuple[tuple[tuple[float, float], ...], ...]
    obstacles: tuple[Obstacle, ...]
    targets: tuple[Target, ...]
    start: tuple[float, float, float]
    description: str = ""
    source: str = ""  # the YAML text the world was parsed from (attached to logs)
    segments: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)), repr=False, compare=False)

    @property
    def target_names(self) -> list[str]:
        return [t.name for t in self.targets]

    def target(self, name: str) -> Target:
        for t in self.targets:
            if t.name == name:
                return t
        raise WorldError(
            f"world {self.name!r} has no target {name!r} (it has: {', '.join(self.target_names) or 'none'})"
        )

    def geometry(self) -> MultiLineString:
        """All walls and obstacle outlines as one shapely geometry (exact reference)."""
        # built in one call (the same geometry as from a list of coordinate pairs, far faster)
        if len(self.segments) == 0:
            return MultiLineString()
        geom: MultiLineString = shapely.multilinestrings(shapely.linestrings(self.segments.reshape(-1, 2, 2)))
        return geom

    def bounds(self) -> tuple[float, float, float, float]:
        s = self.segments
        xs = np.concatenate([s[:, 0], s[:, 2]])
        ys = np.concatenate([s[:, 1], s[:, 3]])
        return float(xs.min()), float(ys.min()), float(xs.max()), float(ys.max())

    def clearance(self, x: float, y: float) -> float:
        """Exact distance (m) from a point to the nearest wall or obstacle."""
        return float(shapely.distance(Point(x, y), self.geometry()))


def _segments_from(walls: list[list[tuple[float, float]]], obstacles: list[Obstacle]) -> np.ndarray:
    segs: list[list[float]] = []
    for line in walls:
        for (ax, ay), (bx, by) in zip(line[:-1], line[1:], strict=True):
            if (ax, ay) != (bx, by):
                segs.append([ax, ay, bx, by])
    for ob in obstacles:
        coords = list(ob.polygon().exterior.coords)
        for (ax, ay), (bx, by) in zip(coords[:-1], coords[1:], strict=True):
            segs.append([ax, ay, bx, by])
    return np.asarray(segs, dtype=np.float64).reshape(-1, 4)


def _num(value: Any, what: str) -> float:
    return number(value, what, error=WorldError)


def _point(value: Any, what: str) -> tuple[float, float]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise WorldError(f"{what} must be a point [x, y], got {value!r}")
    return _num(value[0], what), _num(value[1], what)


def parse_world(data: Any, *, source: str = "", origin: str = "world") -> World:
    """Validate a world mapping (as loaded from YAML) into a :class:`World`."""
    if not isinstance(data, dict):
        raise WorldError(f"{origin}: a world must be a mapping with 'walls' and 'start'")
    walls_in = data.get("walls")
    if (
        isinstance(walls_in, list)
        and sum(len(w) if isinstance(w, list) else 1 for w in walls_in) > MAX_SEGMENTS
    ):
        raise WorldError(f"{origin}: more than {MAX_SEGMENTS} wall points")  # before the slower checks
    validate(data, "world", origin=origin, error=WorldError)
    unknown = sorted(set(data) - _WORLD_KEYS)
    if unknown:
        raise WorldError(
            f"{origin}: unknown key {unknown[0]!r} (valid keys: {', '.join(sorted(_WORLD_KEYS))})"
        )
    for key in ("walls", "start"):
        if key not in data:
            raise WorldError(f"{origin}: missing key {key!r}")
    name = str(data.get("name", Path(origin).stem))
    raw_walls = data["walls"]
    if not isinstance(raw_walls, list) or not raw_walls:
        raise WorldError(f"{origin}: 'walls' must be a non-empty list of polylines")
    walls: list[list[tuple[float, float]]] = []
    for i, line in enumerate(raw_walls):
        if not isinstance(line, list) or len(line) < 2:
            raise WorldError(f"{origin}: walls[{i}] must be a list of at least two [x, y] points")
        pts = [_point(p, f"walls[{i}][{j}]") for j, p in enumerate(line)]
        if LineString(pts).length == 0:
            raise WorldError(f"{origin}: walls[{i}] has zero length")
        walls.append(pts)
    obstacles: list[Obstacle] = []
    for i, ob in enumerate(data.get("obstacles") or []):
        if not isinstance(ob, dict) or len(ob) != 1 or next(iter(ob)) not in ("circle", "polygon"):
            raise WorldError(
                f"{origin}: obstacles[{i}] must be {{circle: [x, y, r]}} or {{polygon: [[x, y], ...]}}"
            )
        if "circle" in ob:
            c = ob["circle"]
            if not isinstance(c, list) or len(c) != 3:
                raise WorldError(f"{origin}: obstacles[{i}].circle must be [x, y, radius]")
            x, y, r = (_num(v, f"obstacles[{i}].circle") for v in c)
            if r <= 0:
                raise WorldError(f"{origin}: obstacles[{i}].circle radius must be positive")
            obstacles.append(Obstacle("circle", circle=(x, y, r)))
        else:
            pts = ob["polygon"]
            if not isinstance(pts, list) or len(pts) < 3:
                raise WorldError(f"{origin}: obstacles[{i}].polygon needs at least three points")
            poly_pts = tuple(_point(p, f"obstacles[{i}].polygon") for p in pts)
            poly = Polygon(poly_pts)
            if not poly.is_valid or poly.area <= 0:
                raise WorldError(f"{origin}: obstacles[{i}].polygon is self-intersecting or empty")
            obstacles.append(Obstacle("polygon", points=poly_pts))
    targets: list[Target] = []
    for i, t in enumerate(data.get("targets") or []):
        if not isinstance(t, dict):
            raise WorldError(f"{origin}: targets[{i}] must be a mapping")
        bad = sorted(set(t) - _TARGET_KEYS)
        if bad:
            raise WorldError(f"{origin}: targets[{i}]: unknown key {bad[0]!r}")
        if "name" not in t or "position" not in t:
            raise WorldError(f"{origin}: targets[{i}] needs 'name' and 'position'")
        tname = str(t["name"])
        if not tname.replace("_", "").isalnum():
            raise WorldError(f"{origin}: targets[{i}] name {tname!r} must be letters, digits and underscores")
        if tname in [x.name for x in targets]:
            raise WorldError(f"{origin}: duplicate target name {tname!r}")
        px, py = _point(t["position"], f"targets[{i}].position")
        targets.append(Target(tname, px, py, _num(t.get("radius", 0.25), f"targets[{i}].radius")))
    start = data["start"]
    if not isinstance(start, list) or len(start) != 3:
        raise WorldError(f"{origin}: 'start' must be [x, y, theta]")
    sx, sy, sth = (_num(v, "start") for v in start)
    _check_size(walls, obstacles, targets, origin)
    segments = _segments_from(walls, obstacles)
    world = World(
        name=name,
        walls=tuple(tuple(w) for w in walls),
        obstacles=tuple(obstacles),
        targets=tuple(targets),
        start=(sx, sy, sth),
        description=str(data.get("description", "")),
        source=source,
        segments=segments,
    )
    check_pose_free(world, (sx, sy, sth), what="start pose")
    return world


#: most wall and obstacle segments of a world (occupancy maps give thousands; a million is an error)
MAX_SEGMENTS = 200_000
#: largest side (m) of a world's bounding box: the planner's and raycaster's grids cover it
MAX_EXTENT_M = 500.0


def _check_size(
    walls: list[list[tuple[float, float]]], obstacles: list[Obstacle], targets: list[Target], origin: str
) -> None:
    """Refuse worlds too big to plan or cast in, before any grid is allocated for them."""
    n = sum(len(w) - 1 for w in walls) + CIRCLE_SIDES * len(obstacles)
    if n > MAX_SEGMENTS:
        raise WorldError(f"{origin}: {n} wall segments, more than the {MAX_SEGMENTS} a world may have")
    xs = [p[0] for w in walls for p in w]
    ys = [p[1] for w in walls for p in w]
    for ob in obstacles:
        if ob.circle is not None:
            x, y, r = ob.circle
            xs += [x - r, x + r]
            ys += [y - r, y + r]
        else:
            xs += [p[0] for p in ob.points]
            ys += [p[1] for p in ob.points]
    w, h = max(xs) - min(xs), max(ys) - min(ys)
    if max(w, h) > MAX_EXTENT_M:
        raise WorldError(
            f"{origin}: the world spans {w:.4g} m x {h:.4g} m; at most {MAX_EXTENT_M:g} m a side is supported"
        )
    if max(w, h) < 0.5:
        raise WorldError(f"{origin}: the world spans {w:.2g} m x {h:.2g} m: too small for a robot")
    for t in targets:
        if not (min(xs) - 1 <= t.x <= max(xs) + 1 and min(ys) - 1 <= t.y <= max(ys) + 1):
            raise WorldError(f"{origin}: target {t.name!r} at ({t.x:g}, {t.y:g}) is outside the map")


def check_pose_free(
    world: World, pose: tuple[float, float, float], *, what: str, radius: float = 0.25
) -> None:
    """Raise :class:`WorldError` when a robot disc at ``pose`` touches a wall or obstacle."""
    x, y, _ = pose
    seg = world.segments
    if len(seg):
        xs, ys = seg[:, [0, 2]], seg[:, [1, 3]]
        if not (xs.min() <= x <= xs.max() and ys.min() <= y <= ys.max()):
            raise WorldError(
                f"{what} ({x:g}, {y:g}) is outside the map (x {xs.min():g}..{xs.max():g}, y {ys.min():g}..{ys.max():g})"
            )
    d = world.clearance(x, y)
    if d < radius:
        raise WorldError(f"{what} ({x:g}, {y:g}) is inside or within {radius:g} m of a wall or obstacle")
    for ob in world.obstacles:
        if ob.polygon().contains(Point(x, y)):
            raise WorldError(f"{what} ({x:g}, {y:g}) is inside an obstacle")
