"""The top-down view of a teleop run as a character grid (the terminal shows it; this draws it).

Pure: a world, a :class:`~lfdfuse.robot.pose.Pose`, a scan and a trail in; lines of text out.
A character cell is twice as tall as it is wide, like a terminal's. The whole map is shown
when it fits at a useful scale, otherwise a window that follows the robot.

Characters: ``#`` wall, ``*`` laser return, ``·`` the path driven, a target's initial in
capitals (``R`` red, ``G`` green, …), and an arrow for the robot and its heading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.world.parse import World

WALL, LASER, TRAIL = "#", "*", "·"
ARROWS = "→↗↑↖←↙↓↘"  # heading sectors of 45°, counter-clockwise from +x
#: the finest and coarsest column width (m) of the view; rows are twice as tall
MIN_CELL_M, MAX_WHOLE_CELL_M, FOLLOW_CELL_M = 0.2, 0.35, 0.25


@dataclass(frozen=True)
class Frame:
    """Which part of the world the grid shows: its top-left corner and the cell size (m)."""

    left_m: float
    top_m: float
    cell_w_m: float
    cols: int
    rows: int

    @property
    def cell_h_m(self) -> float:
        return 2.0 * self.cell_w_m


def frame_for(world: World, pose: Pose, *, cols: int, rows: int) -> Frame:
    """The whole map if it fits with cells of at most 0.35 m, else a window on the robot."""
    x0, y0, x1, y1 = world.bounds()
    cols, rows = max(cols, 8), max(rows, 4)
    cell = max((x1 - x0) / cols, (y1 - y0) / (2 * rows), MIN_CELL_M)
    if cell <= MAX_WHOLE_CELL_M:
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    else:
        cell = FOLLOW_CELL_M
        # snap the window to whole cells so walls do not shimmer as the robot moves
        cx = math.floor(pose.x / cell) * cell + cell / 2
        cy = math.floor(pose.y / (2 * cell)) * 2 * cell + cell
    return Frame(cx - cols / 2 * cell, cy + rows * cell, cell, cols, rows)


def render_map(
    world: World,
    pose: Pose,
    ranges_m: np.ndarray,
    laser: ScanGeometry,
    *,
    cols: int,
    rows: int,
    trail: np.ndarray | None = None,
) -> list[str]:
    """``rows`` strings of ``cols`` characters: walls, trail, laser returns, targets, robot.

    ``ranges_m`` ``(B,)`` holds the laser ranges of ``laser``'s beams (max range = no return);
    ``trail`` ``(M, 2)`` earlier positions in metres.
    """
    f = frame_for(world, pose, cols=cols, rows=rows)
    grid = np.full((f.rows, f.cols), " ", dtype="<U1")

    def put(xs: np.ndarray, ys: np.ndarray, char: str) -> None:
        j = np.floor((np.asarray(xs) - f.left_m) / f.cell_w_m).astype(np.int64)
        i = np.floor((f.top_m - np.asarray(ys)) / f.cell_h_m).astype(np.int64)
        ok = (i >= 0) & (i < f.rows) & (j >= 0) & (j < f.cols)
        grid[i[ok], j[ok]] = char

    if trail is not None and len(trail):
        put(trail[:, 0], trail[:, 1], TRAIL)
    seg = world.segments
    if len(seg):
        length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
        n = np.maximum(2, np.ceil(length / (f.cell_w_m / 2)).astype(np.int64) + 1)
        idx = np.repeat(np.arange(len(seg)), n)
        s = np.concatenate([np.linspace(0.0, 1.0, k) for k in n])
        put(
            seg[idx, 0] + s * (seg[idx, 2] - seg[idx, 0]), seg[idx, 1] + s * (seg[idx, 3] - seg[idx, 1]), WALL
        )
    hit = ranges_m < laser.max_range_m
    if hit.any():
        a = pose.theta + laser.angles[hit]
        put(pose.x + ranges_m[hit] * np.cos(a), pose.y + ranges_m[hit] * np.sin(a), LASER)
    for t in world.targets:
        put(np.array([t.x]), np.array([t.y]), t.name[:1].upper() or "T")
    sector = int(round(pose.theta / (math.pi / 4))) % 8
    put(np.array([pose.x]), np.array([pose.y]), ARROWS[sector])
    return ["".join(row) for row in grid]
