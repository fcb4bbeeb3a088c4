"""``follow`` (FO): toward the nearest laser cluster ahead that moved between scans.

A person walking ahead of the robot is a small cluster of laser returns (their legs) that is
somewhere else at every scan, while walls and furniture stay put. ``follow`` keeps the last
scan's returns in the odometry frame (so the robot's own motion does not make the world seem to
move) and splits the new scan into clusters of neighbouring returns in the front half. A cluster
of a person's size *moved* when its returns lie, on the median, between ``move_m`` and
``jump_m`` from the last scan's. The nearest one that moved is taken and then tracked from scan
to scan (the cluster nearest where it was); ``follow`` points at it (unit length) while it is
there and moved within the last ``hold_scans`` scans — a walker's legs stand still for a scan
now and then. Inapplicable when nothing moved; never applicable without odometry, nor on the
first scan of a log or run.

The state (the last scan, the tracked cluster) is carried from block to block, so a log
computed in blocks and a run computed tick by tick see the same thing. Not in any preset: ask
for it by name (``--behaviors avoid,wander,follow``).

On a real person-following run (a program's, ``../shared/realdata/controllers/``), ``follow`` is
applicable on most ticks where the program drove forward and turns the program's way on most
turning ticks: see ``tests/behaviors/test_follow.py`` for the numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lfdfuse.behaviors.spec import BehaviorParams, BehaviorSpec, Result, Scan


@dataclass(frozen=True)
class FollowParams:
    """What counts as a person that moved (metres)."""

    range_m: float = 4.0  # returns farther than this are not followed
    gap_m: float = 0.2  # neighbouring returns closer than this are one cluster
    max_width_m: float = 0.8  # a wider cluster is a wall or furniture, not a person
    min_points: int = 3  # fewer returns are noise (a leg at 2 m is 3 beams of 1°)
    move_m: float = 0.08  # a cluster whose returns moved less than this (median) stood still
    jump_m: float = 0.8  # one that moved more is something newly revealed, not a walker
    track_m: float = 0.5  # the followed cluster is the one this near where it was a scan ago
    hold_scans: int = 5  # it is followed while it moved within this many scans
    ahead_rad: float = math.pi / 2  # only clusters this far either side of straight ahead


def clusters(points: np.ndarray, gap_m: float) -> list[np.ndarray]:
    """Runs of neighbouring points ``(M, 2)`` (in beam order) closer than ``gap_m`` to the previous.

    >>> [len(c) for c in clusters(np.array([[1.0, 0.0], [1.0, 0.1], [3.0, 0.0]]), 0.2)]
    [2, 1]
    """
    if len(points) == 0:
        return []
    step = np.hypot(*np.diff(points, axis=0).T) if len(points) > 1 else np.zeros(0)
    cuts = np.nonzero(step >= gap_m)[0] + 1
    return np.split(points, cuts)


def _from_frame(point: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """An odometry-frame point into the robot frame at ``pose`` (x, y, heading)."""
    c, s = math.cos(float(pose[2])), math.sin(float(pose[2]))
    dx, dy = float(point[0] - pose[0]), float(point[1] - pose[1])
    return np.array([c * dx + s * dy, -s * dx + c * dy])


def _to_frame(points: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Robot-frame points into the odometry frame of ``pose`` (x, y, heading)."""
    c, s = math.cos(float(pose[2])), math.sin(float(pose[2]))
    return np.column_stack(
        [pose[0] + c * points[:, 0] - s * points[:, 1], pose[1] + s * points[:, 0] + c * points[:, 1]]
    )


class Follow:
    """The ``follow`` primitive. Its state: the last scan's returns and the followed cluster (both
    in the odometry frame), and how many scans ago that cluster last moved."""

    def __init__(self, _name: str, _params: BehaviorParams, params: FollowParams = FollowParams()) -> None:
        self.params = params
        self.last: np.ndarray | None = None
        self.target: np.ndarray | None = None
        self.still = 0

    def reset(self) -> None:
        self.last = self.target = None
        self.still = 0

    def step(self, s: Scan) -> Result:
        vec = np.zeros((s.n, 2))
        app = np.zeros(s.n, dtype=bool)
        pose = s.obs.pose
        if pose is None:
            return Result(vec, app)
        for k in range(s.n):
            use = s.valid[k] & (s.r[k] < self.params.range_m) & (np.abs(s.ang) <= self.params.ahead_rad)
            here = _to_frame(s.r[k][use][:, None] * s.dirs[use], pose[k])
            self._track(here, pose[k, :2])
            self.last = here
            if self.target is not None:
                local = _from_frame(self.target, pose[k])
                r = float(np.hypot(local[0], local[1]))
                if r > 1e-9:
                    vec[k] = local / r
                    app[k] = True
        return Result(vec, app)

    def _track(self, here: np.ndarray, robot_xy: np.ndarray) -> None:
        """Follow the tracked cluster to where it is now, or take the nearest one that moved."""
        p = self.params
        found: list[tuple[np.ndarray, bool]] = []  # (centroid, moved) of person-sized clusters
        for cl in clusters(here, p.gap_m):
            if len(cl) < p.min_points or float(np.hypot(*(cl[-1] - cl[0]))) > p.max_width_m:
                continue
            moved = False
            if self.last is not None and len(self.last):
                d = np.sqrt(((cl[:, None, :] - self.last[None, :, :]) ** 2).sum(axis=2)).min(axis=1)
                moved = p.move_m <= float(np.median(d)) <= p.jump_m
            found.append((cl.mean(axis=0), moved))
        if self.target is not None:
            near = [(float(np.hypot(*(c - self.target))), c, m) for c, m in found]
            near = [x for x in near if x[0] <= p.track_m]
            if near:
                _, c, m = min(near, key=lambda x: x[0])
                self.target, self.still = c, 0 if m else self.still + 1
                if self.still <= p.hold_scans:
                    return
            self.target = None
        movers = [c for c, m in found if m]
        if movers:
            self.target = min(movers, key=lambda c: float(np.hypot(*(c - robot_xy))))
            self.still = 0


SPECS = (
    BehaviorSpec(
        "follow",
        "FO",
        "#D55E00",
        20,
        Follow,
        inputs=frozenset({"laser", "odometry"}),
        meaning="toward the nearest laser cluster that moved since the last scan (a person walking ahead)",
    ),
)
