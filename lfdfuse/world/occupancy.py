"""Occupancy maps as worlds (DESIGN §2): a ROS ``map_server`` YAML and its PGM/PNG image.

Cells are read as map_server reads them (mean of the colour channels, ``negate``, the
``occupied_thresh``/``free_thresh`` of the YAML, ``mode`` trinary, scale or raw). Every cell
that is not free is a wall: occupied and unknown alike. The boundary of the non-free cells is
traced (marching squares at the cell edges, outside the image counts as wall) and simplified
to the map resolution, giving wall polylines in metres in the map frame. Free pockets too
narrow to hold the robot anywhere are filled first: only their inside would see those walls.

Without a start pose the robot starts at the free point farthest from any wall in the largest
free region it fits in, facing the longest free line of sight.

The world's ``source`` is a generated world YAML with the same walls and start, so a log's
world attachment loads again without the image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import shapely
import yaml

from lfdfuse.errors import WorldError
from lfdfuse.validate import number
from lfdfuse.world.parse import World, parse_world

#: the keys of a map_server YAML (ROS 1 and ROS 2)
MAP_KEYS = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode")
MODES = ("trinary", "scale", "raw")
#: bounds: a bigger map is an error, not an out-of-memory
MAX_CELLS = 16_000_000
MAX_SEGMENTS = 200_000
MAX_COORDINATE_M = 1e6
#: the robot a default start must hold (DESIGN §3)
ROBOT_RADIUS_M = 0.25
#: the shade map_saver writes for unknown cells
UNKNOWN_SHADE = 205
#: the longest line of sight (m) considered when choosing the start heading
_SIGHT_M = 8.0


@dataclass(frozen=True)
class MapInfo:
    """A parsed map_server YAML. ``origin`` is the pose of the lower-left cell corner (m, m, rad)."""

    image: Path
    resolution_m: float
    origin: tuple[float, float, float]
    negate: bool
    occupied_thresh: float
    free_thresh: float
    mode: str = "trinary"


def is_map_yaml(data: Any) -> bool:
    """Whether a loaded YAML document is a map_server map (it names an image and a resolution)."""
    return isinstance(data, dict) and "image" in data and "resolution" in data and "walls" not in data


def _number(data: dict[str, Any], key: str, origin: str, *, lo: float, hi: float) -> float:
    return number(data[key], f"{origin}: {key!r}", error=WorldError, lo=lo, hi=hi)


def parse_map_yaml(data: dict[str, Any], *, folder: Path, origin: str) -> MapInfo:
    """Validate a map_server mapping; ``image`` is relative to ``folder`` unless absolute."""
    unknown = sorted(set(data) - set(MAP_KEYS))
    if unknown:
        raise WorldError(f"{origin}: unknown map key {unknown[0]!r} (map keys: {', '.join(MAP_KEYS)})")
    for key in ("image", "resolution", "origin", "occupied_thresh", "free_thresh"):
        if key not in data:
            raise WorldError(f"{origin}: map is missing key {key!r}")
    if not isinstance(data["image"], str) or not data["image"]:
        raise WorldError(f"{origin}: 'image' must be a file name, got {data['image']!r}")
    resolution = _number(data, "resolution", origin, lo=1e-4, hi=100.0)
    if resolution <= 0:
        raise WorldError(f"{origin}: 'resolution' must be positive")
    pose = data["origin"]
    if not isinstance(pose, list) or len(pose) not in (2, 3):
        raise WorldError(f"{origin}: 'origin' must be [x, y, yaw], got {pose!r}")
    xyz = [_number({"origin": v}, "origin", origin, lo=-MAX_COORDINATE_M, hi=MAX_COORDINATE_M) for v in pose]
    negate = data.get("negate", 0)
    if negate not in (0, 1):  # True and False compare equal to 1 and 0
        raise WorldError(f"{origin}: 'negate' must be 0 or 1, got {negate!r}")
    occupied = _number(data, "occupied_thresh", origin, lo=0.0, hi=1.0)
    free = _number(data, "free_thresh", origin, lo=0.0, hi=1.0)
    if free > occupied:
        raise WorldError(f"{origin}: 'free_thresh' ({free:g}) is above 'occupied_thresh' ({occupied:g})")
    mode = data.get("mode", "trinary")
    if mode not in MODES:
        raise WorldError(f"{origin}: 'mode' must be one of {', '.join(MODES)}, got {mode!r}")
    image = Path(data["image"])
    return MapInfo(
        image=image if image.is_absolute() else folder / image,
        resolution_m=resolution,
        origin=(xyz[0], xyz[1], xyz[2] if len(xyz) == 3 else 0.0),
        negate=bool(negate),
        occupied_thresh=occupied,
        free_thresh=free,
        mode=str(mode),
    )


def read_shades(path: Path, *, origin: str) -> np.ndarray:
    """The image as ``(H, W)`` float shades 0…255 (mean of the colour channels, alpha ignored)."""
    from PIL import Image  # the image stack, here and below, only where a map image is read

    try:
        opened = Image.open(path)
    except FileNotFoundError:
        raise WorldError(f"{origin}: map image {path} not found") from None
    except (OSError, Image.DecompressionBombError) as exc:
        raise WorldError(f"{origin}: cannot read map image {path} ({exc})") from exc
    with opened:
        w, h = opened.size
        if w * h > MAX_CELLS:
            raise WorldError(
                f"{origin}: map image {path.name} is {w}×{h} cells (at most {MAX_CELLS:,} allowed)"
            )
        img: Image.Image = opened
        if img.mode == "P":
            img = img.convert("RGBA" if "transparency" in img.info else "RGB")
        elif img.mode == "1":
            img = img.convert("L")
        if img.mode not in ("L", "LA", "RGB", "RGBA"):
            raise WorldError(f"{origin}: map image {path.name} has unsupported pixel mode {img.mode}")
        try:
            pixels = np.asarray(img, dtype=np.float64)
        except OSError as exc:
            raise WorldError(f"{origin}: map image {path.name} is truncated or corrupt ({exc})") from exc
        has_alpha = img.mode in ("LA", "RGBA")
    if pixels.ndim == 2:
        return pixels
    return np.asarray(pixels[:, :, : pixels.shape[2] - int(has_alpha)].mean(axis=2))


def free_cells(shades: np.ndarray, info: MapInfo) -> np.ndarray:
    """Free cells ``(H, W)`` bool, read as map_server reads them.

    In trinary mode the saver's unknown shade (205) is unknown whatever ``free_thresh`` says:
    ROS 2's map_saver writes ``free_thresh: 0.25``, which would otherwise read every unknown
    cell as free (slam_toolbox#587, navigation2#5138).
    """
    value = 255.0 - shades if info.negate else shades
    if info.mode == "raw":
        # the value is the occupancy in percent; above 100 (255 = -1) is unknown
        return (value <= 100.0) & (value / 100.0 < info.free_thresh)
    occupancy = (255.0 - value) / 255.0
    free = occupancy < info.free_thresh
    if info.mode == "trinary":
        free &= value != UNKNOWN_SHADE
    return free


def _clearance_px(free: np.ndarray) -> np.ndarray:
    """Distance (cells) from each free cell centre to the nearest non-free cell edge (0 if not free)."""
    from scipy import ndimage

    padded = np.pad(free, 1, constant_values=False)
    return np.asarray(np.maximum(ndimage.distance_transform_edt(padded)[1:-1, 1:-1] - 0.5, 0.0))


def fill_pockets(free: np.ndarray, *, radius_px: float) -> np.ndarray:
    """``free`` without the 4-connected free regions where no cell has ``radius_px`` of clearance."""
    from scipy import ndimage

    labels, n = ndimage.label(free)
    if n == 0:
        return free
    best = ndimage.maximum(_clearance_px(free), labels, index=np.arange(1, n + 1))
    keep = np.concatenate([[False], np.asarray(best) >= radius_px])
    return np.asarray(keep[labels])


def wall_lines(free: np.ndarray, *, tolerance_px: float) -> list[np.ndarray]:
    """Boundaries of the non-free cells as polylines ``(N, 2)`` of (row, col) cell coordinates.

    Marching squares at level 0.5 puts the boundary on the cell edges; walls join diagonally
    (a free diagonal pinch is closed); then Douglas–Peucker simplification to ``tolerance_px``.
    """
    from skimage import measure

    solid = np.pad(~free, 1, constant_values=True).astype(np.float32)
    contours = measure.find_contours(solid, 0.5, fully_connected="high")
    if not contours:
        return []
    lines = shapely.simplify(
        np.array([shapely.LineString(c - 1.0) for c in contours], dtype=object),
        tolerance_px,
        preserve_topology=True,
    )
    out = [shapely.get_coordinates(g) for g in lines]
    return [c for c in out if len(c) >= 2 and np.ptp(c, axis=0).max() > 0]


def default_start(free: np.ndarray, *, radius_px: float) -> tuple[int, int, float]:
    """``(row, col, heading)``: the free cell farthest from walls in the largest region the robot fits in.

    The heading (rad, in the image frame: 0 = +col, π/2 = −row) is the longest line of sight
    among 36 directions. Raises :class:`WorldError` when the robot fits nowhere.
    """
    from scipy import ndimage

    clear = _clearance_px(free)
    room = clear > radius_px
    labels, n = ndimage.label(room)
    if n == 0:
        raise WorldError(f"no free space wide enough for the robot (radius {ROBOT_RADIUS_M:g} m)")
    largest = int(np.argmax(np.bincount(labels.ravel())[1:])) + 1
    r, c = np.unravel_index(int(np.argmax(np.where(labels == largest, clear, -1.0))), clear.shape)
    return int(r), int(c), _open_heading(free, int(r), int(c))


def _open_heading(free: np.ndarray, r: int, c: int, *, reach_px: float = 400.0) -> float:
    angles = np.arange(36) * (2 * math.pi / 36)
    steps = np.arange(1, int(reach_px * 2) + 1) * 0.5
    rows = np.rint(r - np.sin(angles)[:, None] * steps[None, :]).astype(np.int64)
    cols = np.rint(c + np.cos(angles)[:, None] * steps[None, :]).astype(np.int64)
    inside = (rows >= 0) & (rows < free.shape[0]) & (cols >= 0) & (cols < free.shape[1])
    open_ = inside & free[np.clip(rows, 0, free.shape[0] - 1), np.clip(cols, 0, free.shape[1] - 1)]
    blocked = ~open_
    first = np.where(blocked.any(axis=1), blocked.argmax(axis=1), len(steps))
    return float(angles[int(np.argmax(first))])


def _fmt(v: float) -> str:
    """A float for YAML, to the micrometre, always with a dot (PyYAML reads ``1e-05`` as text)."""
    text = f"{v:.6f}".rstrip("0")
    return text + "0" if text.endswith(".") else text


def render_world_yaml(
    *, name: str, description: str, walls: list[list[tuple[str, str]]], start: tuple[str, str, str]
) -> str:
    """World YAML text (DESIGN §2) from already formatted numbers."""
    head = yaml.safe_dump({"name": name, "description": description}, sort_keys=False, width=1 << 16)
    rows = ["  - [" + ", ".join(f"[{x}, {y}]" for x, y in line) + "]" for line in walls]
    return head + "walls:\n" + "\n".join(rows) + f"\nstart: [{start[0]}, {start[1]}, {start[2]}]\n"


def world_from_map(data: dict[str, Any], *, path: Path, radius_m: float = ROBOT_RADIUS_M) -> World:
    """The world of a map_server YAML mapping ``data`` read from ``path``."""
    origin = str(path)
    info = parse_map_yaml(data, folder=path.parent, origin=origin)
    shades = read_shades(info.image, origin=origin)
    h, w = shades.shape
    res = info.resolution_m
    free = fill_pockets(free_cells(shades, info), radius_px=radius_m / res)
    if not free.any():
        raise WorldError(f"{origin}: the map has no free space the robot fits in")
    lines = wall_lines(free, tolerance_px=1.0)
    n_seg = sum(len(c) - 1 for c in lines)
    if n_seg > MAX_SEGMENTS:
        raise WorldError(
            f"{origin}: the map gives {n_seg:,} wall segments (at most {MAX_SEGMENTS:,} allowed)"
        )
    ox, oy, yaw = info.origin
    cos_y, sin_y = math.cos(yaw), math.sin(yaw)

    def to_map(rc: np.ndarray) -> np.ndarray:
        """(row, col) cell coordinates → (x, y) metres in the map frame."""
        u = (rc[:, 1] + 0.5) * res
        v = (h - rc[:, 0] - 0.5) * res
        return np.column_stack([ox + cos_y * u - sin_y * v, oy + sin_y * u + cos_y * v])

    walls = [[(_fmt(x), _fmt(y)) for x, y in to_map(c)] for c in lines]
    # the simplified walls may stand up to one cell into the free space: keep a cell's margin
    try:
        r, c, heading = default_start(free, radius_px=radius_m / res + 1.0)
    except WorldError as exc:
        raise WorldError(f"{origin}: {exc}") from None
    sx, sy = to_map(np.array([[r, c]], dtype=np.float64))[0]
    theta = math.atan2(math.sin(heading + yaw), math.cos(heading + yaw))
    start = (_fmt(sx), _fmt(sy), _fmt(theta))
    name = path.stem
    description = f"occupancy map {info.image.name}: {w}×{h} cells of {res:g} m"
    text = render_world_yaml(name=name, description=description, walls=walls, start=start)
    world_data = {
        "name": name,
        "description": description,
        "walls": [[[float(x), float(y)] for x, y in line] for line in walls],
        "start": [float(v) for v in start],
    }
    return parse_world(world_data, source=text, origin=origin)
