"""A grid planner over the free space, inflated by the robot radius.

Cells of ``resolution_m`` whose centre is farther than the robot radius (plus a small margin)
from every segment, and connected to the start, are free. Cost-to-go fields are computed with
Dijkstra over the 8-connected grid; each step costs its length times a clearance penalty that
keeps paths in the middle of corridors. Teachers follow the field downhill.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.world.model import World
from lfdfuse.world.raycast import _point_segment_distance

_NEIGHBOURS = ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1))


@dataclass(frozen=True)
class PlannerParams:
    resolution_m: float = 0.2
    margin_m: float = 0.05
    #: paths pay extra near walls: cost × (1 + penalty · max(0, 1 − clearance / comfort))
    comfort_m: float = 1.2
    penalty: float = 4.0


class Planner:
    """Free-space grid of a world with cost-to-go fields to goal points."""

    def __init__(
        self, world: World, *, robot_radius_m: float, params: PlannerParams = PlannerParams()
    ) -> None:
        self.params = params
        res = params.resolution_m
        x0, y0, x1, y1 = world.bounds()
        self.x0, self.y0 = x0, y0
        self.nx = int(math.ceil((x1 - x0) / res))
        self.ny = int(math.ceil((y1 - y0) / res))
        cx = x0 + (np.arange(self.nx) + 0.5) * res
        cy = y0 + (np.arange(self.ny) + 0.5) * res
        gx, gy = np.meshgrid(cx, cy, indexing="ij")
        px, py = gx.ravel(), gy.ravel()
        clear = np.empty(px.shape)
        chunk = max(1, 2_000_000 // max(1, len(world.segments)))
        for i in range(0, len(px), chunk):
            clear[i : i + chunk] = _point_segment_distance(
                px[i : i + chunk], py[i : i + chunk], world.segments
            ).min(axis=1)
        self.clearance = clear.reshape(self.nx, self.ny)
        passable = self.clearance > robot_radius_m + params.margin_m
        # free space = the passable cells connected to the start pose
        start = self.cell(world.start[0], world.start[1])
        self.free = self._flood(passable, start)
        self.step_cost = 1.0 + params.penalty * np.maximum(0.0, 1.0 - self.clearance / params.comfort_m)
        self._fields: dict[tuple[int, int], np.ndarray] = {}

    def cell(self, x: float, y: float) -> tuple[int, int]:
        res = self.params.resolution_m
        i = min(max(int((x - self.x0) / res), 0), self.nx - 1)
        j = min(max(int((y - self.y0) / res), 0), self.ny - 1)
        return i, j

    def centre(self, i: int, j: int) -> tuple[float, float]:
        res = self.params.resolution_m
        return self.x0 + (i + 0.5) * res, self.y0 + (j + 0.5) * res

    def _flood(self, passable: np.ndarray, start: tuple[int, int]) -> np.ndarray:
        free = np.zeros_like(passable)
        if not passable[start]:
            start = self.nearest_free(passable, *start)
        stack = [start]
        free[start] = True
        while stack:
            i, j = stack.pop()
            for di, dj in _NEIGHBOURS[:4]:
                a, b = i + di, j + dj
                if 0 <= a < self.nx and 0 <= b < self.ny and passable[a, b] and not free[a, b]:
                    free[a, b] = True
                    stack.append((a, b))
        return free

    def nearest_free(self, mask: np.ndarray, i: int, j: int) -> tuple[int, int]:
        idx = np.argwhere(mask)
        if len(idx) == 0:
            raise ConfigError("the world has no free space for the robot")
        k = int(np.argmin((idx[:, 0] - i) ** 2 + (idx[:, 1] - j) ** 2))
        return int(idx[k, 0]), int(idx[k, 1])

    def field(self, x: float, y: float) -> np.ndarray:
        """Cost-to-go ``(nx, ny)`` to the free cell nearest ``(x, y)``; inf where unreachable."""
        goal = self.cell(x, y)
        if not self.free[goal]:
            goal = self.nearest_free(self.free, *goal)
        cached = self._fields.get(goal)
        if cached is not None:
            return cached
        dist = np.full((self.nx, self.ny), np.inf)
        dist[goal] = 0.0
        heap: list[tuple[float, int, int]] = [(0.0, goal[0], goal[1])]
        free, cost = self.free, self.step_cost
        nx, ny = self.nx, self.ny
        while heap:
            d, i, j = heapq.heappop(heap)
            if d > dist[i, j]:
                continue
            for di, dj in _NEIGHBOURS:
                a, b = i + di, j + dj
                if 0 <= a < nx and 0 <= b < ny and free[a, b]:
                    if di and dj and not (free[i + di, j] and free[i, j + dj]):
                        continue  # no corner cutting
                    nd = d + (1.4142135623730951 if di and dj else 1.0) * 0.5 * (cost[i, j] + cost[a, b])
                    if nd < dist[a, b]:
                        dist[a, b] = nd
                        heapq.heappush(heap, (nd, a, b))
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
        """The free cell with the largest cost-to-go from ``(x, y)`` (for touring)."""
        fld = self.field(x, y)
        masked = np.where(np.isfinite(fld), fld, -1.0)
        i, j = np.unravel_index(int(np.argmax(masked)), masked.shape)
        return self.centre(int(i), int(j))
