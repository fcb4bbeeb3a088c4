"""A grid planner over the free space, inflated by the robot radius.

Cells of ``resolution_m`` whose centre is farther than the robot radius (plus a small margin)
from every segment are passable; those 4-connected to the world's start are free (goals where
the robot does not fit snap to them), and a robot started in another region tours that one.
Cost-to-go fields are computed with Dijkstra over the 8-connected grid (scikit-image's ``MCP_Geometric``): a step costs its length
times the mean of its two cells' clearance penalties, which keeps paths in the middle of
corridors. Teachers follow the field downhill.

Setup stays cheap on occupancy maps of thousands of walls: the clearance of a cell is computed
exactly only from the segments within ``comfort_m`` of it (found per segment, never cells ×
segments); farther cells pay no penalty and are estimated with a distance transform.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from skimage.graph import MCP_Geometric

from lfdfuse.errors import ConfigError
from lfdfuse.world.parse import World
from lfdfuse.world.raycast import near_pairs

_NEIGHBOURS = ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1))
#: cost-to-go fields kept per planner (each is one float per cell): at most 64, and 20 M floats
_FIELDS_KEPT = 64
_FIELD_CELLS_KEPT = 20_000_000


@dataclass(frozen=True)
class PlannerParams:
    resolution_m: float = 0.2
    margin_m: float = 0.05
    #: paths pay extra near walls: cost × (1 + penalty · max(0, 1 − clearance / comfort))
    comfort_m: float = 1.2
    penalty: float = 4.0


def clearance_grid(
    segments: np.ndarray, *, x0: float, y0: float, resolution_m: float, nx: int, ny: int, exact_m: float
) -> np.ndarray:
    """Distance (m) ``(nx, ny)`` from each cell centre to the nearest segment.

    Exact wherever it is at most ``exact_m``; elsewhere an estimate above ``exact_m`` (the
    distance in cells to the nearest exact cell, by a distance transform).
    """
    clear = np.full(nx * ny, np.inf)
    for _, i, j, d in near_pairs(segments, x0=x0, y0=y0, cell_m=resolution_m, nx=nx, ny=ny, reach_m=exact_m):
        np.minimum.at(clear, i * ny + j, d)
    grid = clear.reshape(nx, ny)
    far = ~np.isfinite(grid)
    if far.any():
        if far.all():
            grid[:] = exact_m
        else:
            # a far cell is more than exact_m from every segment, and at most a few cells more
            # than its nearest near cell's clearance (≤ exact_m): a mid estimate, above exact_m
            hops = ndimage.distance_transform_edt(far)
            grid[far] = exact_m + (hops[far] - 0.5) * resolution_m
    return grid


class Planner:
    """Free-space grid of a world with cost-to-go fields to goal points."""

    def __init__(
        self, world: World, *, robot_radius_m: float, params: PlannerParams = PlannerParams()
    ) -> None:
        self.params = params
        res = params.resolution_m
        x0, y0, x1, y1 = world.bounds()
        self.x0, self.y0 = x0, y0
        self.nx = max(1, int(math.ceil((x1 - x0) / res)))
        self.ny = max(1, int(math.ceil((y1 - y0) / res)))
        passable_m = robot_radius_m + params.margin_m
        #: clearance (m) per cell: exact up to comfort_m (where costs and passability are decided)
        self.clearance = clearance_grid(
            world.segments,
            x0=x0,
            y0=y0,
            resolution_m=res,
            nx=self.nx,
            ny=self.ny,
            exact_m=max(params.comfort_m, passable_m),
        )
        #: cells the robot fits in, and their 4-connected regions (labels from 1; 0 = blocked)
        self.passable = self.clearance > passable_m
        self.regions, _ = ndimage.label(self.passable)
        # free space = the passable cells 4-connected to the world's start pose
        start = self.cell(world.start[0], world.start[1])
        if not self.passable[start]:
            start = self.nearest_free(self.passable, *start)
        self.free = self.regions == self.regions[start]
        self.step_cost = 1.0 + params.penalty * np.maximum(0.0, 1.0 - self.clearance / params.comfort_m)
        self._mcp = MCP_Geometric(np.where(self.passable, self.step_cost, np.inf), fully_connected=True)
        self._fields: dict[tuple[int, int], np.ndarray] = {}

    def cell(self, x: float, y: float) -> tuple[int, int]:
        res = self.params.resolution_m
        i = min(max(int((x - self.x0) / res), 0), self.nx - 1)
        j = min(max(int((y - self.y0) / res), 0), self.ny - 1)
        return i, j

    def centre(self, i: int, j: int) -> tuple[float, float]:
        res = self.params.resolution_m
        return self.x0 + (i + 0.5) * res, self.y0 + (j + 0.5) * res

    def nearest_free(self, mask: np.ndarray, i: int, j: int) -> tuple[int, int]:
        idx = np.argwhere(mask)
        if len(idx) == 0:
            raise ConfigError("the world has no free space for the robot")
        k = int(np.argmin((idx[:, 0] - i) ** 2 + (idx[:, 1] - j) ** 2))
        return int(idx[k, 0]), int(idx[k, 1])

    def field(self, x: float, y: float) -> np.ndarray:
        """Cost-to-go ``(nx, ny)`` to ``(x, y)``; inf where unreachable.

        The goal is the cell of ``(x, y)`` when the robot fits there (in any region: a robot
        started elsewhere tours its own region), else the nearest free cell. A step between
        neighbouring cells of the goal's region costs its length (in cells) times the mean of
        their step costs. Fields are cached per goal cell.
        """
        goal = self.cell(x, y)
        if not self.passable[goal]:
            goal = self.nearest_free(self.free, *goal)
        return self._field_to(goal)

    def _field_to(self, goal: tuple[int, int]) -> np.ndarray:
        cached = self._fields.get(goal)
        if cached is not None:
            return cached
        dist, _ = self._mcp.find_costs([goal])
        # diagonal steps may touch another region corner to corner: keep to the goal's
        dist = np.where(self.regions == self.regions[goal], dist, np.inf)
        dist.setflags(write=False)
        if len(self._fields) >= max(1, min(_FIELDS_KEPT, _FIELD_CELLS_KEPT // dist.size)):
            self._fields.pop(next(iter(self._fields)))
        self._fields[goal] = dist
        return dist

    def reachable(self, x: float, y: float, fld: np.ndarray) -> bool:
        return bool(np.isfinite(fld[self.cell(x, y)]))

    def follow(self, x: float, y: float, fld: np.ndarray, cells: int) -> tuple[float, float]:
        """The point ``cells`` steps downhill of ``(x, y)`` on a cost-to-go field."""
        i, j = self.cell(x, y)
        if not np.isfinite(fld[i, j]):
            i, j = self.nearest_free(np.isfinite(fld), i, j)
        for _ in range(cells):
            best = (fld[i, j], i, j)
            for di, dj in _NEIGHBOURS:
                a, b = i + di, j + dj
                if 0 <= a < self.nx and 0 <= b < self.ny and fld[a, b] < best[0]:
                    best = (fld[a, b], a, b)
            if best[1:] == (i, j):
                break
            i, j = best[1], best[2]
        return self.centre(i, j)

    def farthest(self, x: float, y: float) -> tuple[float, float]:
        """The cell with the largest cost-to-go from ``(x, y)`` in its region (for touring).

        From a point where the robot does not fit, the nearest cell where it does.
        """
        here = self.cell(x, y)
        if not self.passable[here]:
            here = self.nearest_free(self.passable, *here)
        fld = self._field_to(here)
        masked = np.where(np.isfinite(fld), fld, -1.0)
        i, j = np.unravel_index(int(np.argmax(masked)), masked.shape)
        return self.centre(int(i), int(j))
