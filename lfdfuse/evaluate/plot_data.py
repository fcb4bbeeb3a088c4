"""What a plot shows of a file: logs decoded into plot data, through the readers of
:mod:`lfdfuse.log` and :mod:`lfdfuse.segment` (below :mod:`lfdfuse.viz`, which only draws).

A demo, segmented or run MCAP becomes a :class:`PathData` (the map, the path on the clock of
the laser scans, what part of the task each tick belongs to, BAC changes, goals reached and
collisions); a fusion table is read with :func:`lfdfuse.network.table.load_table`. Nothing
here draws: the figures take these dataclasses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Literal

import numpy as np
import shapely

from lfdfuse.behaviors.spec import attract_target
from lfdfuse.errors import LfdError, LogError
from lfdfuse.files import parse_yaml
from lfdfuse.log import lfd
from lfdfuse.log.codec import MessageError
from lfdfuse.log.reader import file_info, hold, iter_messages, read_run
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.segment.read import network_ticks, read_segmented
from lfdfuse.sim.robot import RobotParams
from lfdfuse.world.model import World, builtin_names, load_world, parse_world

LogKind = Literal["demo", "segmented", "run"]

#: the part of a correction run the person drove (not the network's step it happened in)
PERSON_PART = "the person (took over)"


@dataclass(frozen=True)
class GoalMark:
    """A goal reached: the target's name, where the robot was (m) and when (s from the start)."""

    target: str
    x: float
    y: float
    t_s: float


@dataclass(frozen=True)
class PathData:
    """What a log shows on a map.

    ``t_s (N,)`` seconds from the first scan, ``pose (N, 3)`` x, y (m), yaw (rad); ``part (N,)``
    indexes ``part_names`` (the goal segment or the network step of each tick, or
    :data:`PERSON_PART` where a person had taken over; -1: none, e.g. a run after its last goal); ``bac (N,)`` the BAC of each tick (None for a plain demo);
    ``collisions`` tick indices where a contact began.
    """

    kind: LogKind
    source: str
    world: World | None
    t_s: np.ndarray
    pose: np.ndarray
    part: np.ndarray
    part_names: tuple[str, ...]
    bac: np.ndarray | None
    goals: tuple[GoalMark, ...]
    collisions: np.ndarray
    metadata: dict[str, str] = field(default_factory=dict)
    #: without a map: the laser returns ``(K, 2)`` (m) in the pose's frame (odometry for an
    #: imported log), the scans' own picture of the walls; None with a map
    scan_points: np.ndarray | None = None

    @property
    def part_label(self) -> str:
        return {"demo": "demonstration", "segmented": "goal segment", "run": "network step"}[self.kind]

    def bac_changes(self) -> np.ndarray:
        """Indices of the ticks whose BAC differs from the tick before."""
        if self.bac is None or len(self.bac) < 2:
            return np.zeros(0, dtype=np.int64)
        return np.nonzero(self.bac[1:] != self.bac[:-1])[0] + 1


def log_kind(path: str | Path) -> LogKind:
    """``segmented`` (has ``/lfd/segment``; a segmented correction keeps its run's ``/lfd/step``),
    ``run`` (has ``/lfd/step``) or ``demo``."""
    channels = file_info(path).channels
    if "/lfd/segment" in channels:
        return "segmented"
    if "/lfd/step" in channels:
        return "run"
    return "demo"


def world_of(world_yaml: str | None, metadata: dict[str, str], source: str) -> World | None:
    """The world a log was recorded in: its attachment, else a built-in world it names, else None."""
    if world_yaml:
        try:
            return parse_world(parse_yaml(world_yaml, origin=f"{source}:world.yaml"), origin=source)
        except LfdError:
            pass  # an attachment we cannot parse: fall back to the name, or draw without a map
    name = metadata.get("world", "")
    return load_world(name) if name in builtin_names() else None


def contacts(
    pose: np.ndarray, v_mps: np.ndarray, world: World | None, *, radius_m: float = RobotParams().radius_m
) -> np.ndarray:
    """Ticks where a contact with a wall began: a forward command that did not move the robot,
    against a wall (the simulator refuses such moves and counts one collision per contact).

    ``pose (N, 3)``, ``v_mps (N,)`` the command of each tick.
    """
    if world is None or len(pose) < 2:
        return np.zeros(0, dtype=np.int64)
    step = np.hypot(np.diff(pose[:, 0]), np.diff(pose[:, 1]))
    near = shapely.distance(shapely.points(pose[:-1, :2]), world.geometry()) < radius_m + 0.1
    stuck = (np.abs(v_mps[:-1]) > 0.02) & (step < 1e-4) & near
    onset = stuck & ~np.concatenate([[False], stuck[:-1]])
    return np.nonzero(onset)[0].astype(np.int64)


def _goal_name(goal: str | None) -> str | None:
    if goal is None:
        return None
    return attract_target(goal) or goal


#: at most this many laser returns are kept for a plot (every k-th scan past it)
MAX_SCAN_POINTS = 2_000_000


def mount_offset(metadata: dict[str, str]) -> tuple[float, float]:
    """Where the laser sits on the robot (m, base frame): the log's ``laser_mount`` (an imported
    or live log; its yaw is already in the scan's angles), else at the base."""
    try:
        x, y, _yaw = (float(v) for v in metadata.get("laser_mount", "0,0,0").split(","))
    except ValueError:
        return (0.0, 0.0)
    return (x, y) if math.isfinite(x) and math.isfinite(y) else (0.0, 0.0)


def scan_points(
    ranges_m: np.ndarray,
    geometry: ScanGeometry,
    pose: np.ndarray,
    *,
    mount_xy: tuple[float, float] = (0.0, 0.0),
    max_points: int = MAX_SCAN_POINTS,
) -> np.ndarray:
    """The laser returns ``(K, 2)`` (m) in the frame of ``pose``: beam ``i`` of scan ``t`` at
    ``pose[t] ∘ (mount + r·(cos aᵢ, sin aᵢ))``; beams without a return (at the max range, or not
    finite) are left out. ``ranges_m (N, B)``, ``pose (N, 3)``; every k-th scan when there would
    be more than ``max_points``.

    >>> g = ScanGeometry(0.0, math.pi / 2, 2, 5.0)
    >>> scan_points(np.array([[1.0, 5.0]]), g, np.array([[1.0, 2.0, math.pi / 2]])).round(6).tolist()
    [[1.0, 3.0]]
    """
    n, b = ranges_m.shape
    if n == 0 or b == 0:
        return np.zeros((0, 2))
    step = max(1, math.ceil(n * b / max(max_points, 1)))
    r, p = ranges_m[::step], pose[::step]
    hit = np.isfinite(r) & (r < geometry.max_range_m - 1e-6) & (r > 0.0)
    r = np.where(hit, r, 0.0)
    a = geometry.angles[None, :]
    bx = mount_xy[0] + r * np.cos(a)  # (n', B) in the base frame
    by = mount_xy[1] + r * np.sin(a)
    c, s = np.cos(p[:, 2:3]), np.sin(p[:, 2:3])
    wx, wy = p[:, 0:1] + c * bx - s * by, p[:, 1:2] + s * bx + c * by
    return np.column_stack([wx[hit], wy[hit]])


def load_log(path: str | Path) -> PathData:
    """A demo, segmented or run MCAP as plot data; a clear error if it has no path to draw."""
    src = str(path)
    kind = log_kind(path)
    run = read_run(path)
    if run.pose is None:
        raise LogError(f"{src}: the log has no /pose: there is no path to draw")
    t0 = int(run.t_ns[0])
    t_s = (run.t_ns - t0).astype(np.float64) / 1e9
    pose = run.pose
    world = world_of(run.world_yaml, run.metadata, src)
    v = run.cmd_v_mps[hold(run.cmd_t_ns, run.t_ns)] if len(run.cmd_t_ns) else np.zeros(len(run))
    hits = contacts(pose, v, world)
    if kind == "segmented":
        data = _segmented(path, src, world, t_s, pose, run.t_ns, hits, run.metadata)
    elif kind == "run":
        data = _run(path, src, world, t_s, pose, run.t_ns, hits, run.metadata)
    else:
        data = _demo(run.metadata, world, src, t_s, pose, hits)
    if world is None:  # no map: the scans draw the walls they saw
        mount = mount_offset(run.metadata)
        return replace(data, scan_points=scan_points(run.ranges_m, run.geometry, pose, mount_xy=mount))
    return data


def _demo(
    meta: dict[str, str], world: World | None, src: str, t_s: np.ndarray, pose: np.ndarray, hits: np.ndarray
) -> PathData:
    return PathData(
        "demo",
        src,
        world,
        t_s,
        pose,
        np.zeros(len(t_s), dtype=np.int64),
        (str(meta.get("teacher") or "demonstration"),),
        None,
        (),
        hits,
        meta,
    )


def _segmented(
    path: str | Path,
    src: str,
    world: World | None,
    t_s: np.ndarray,
    pose: np.ndarray,
    scan_t: np.ndarray,
    hits: np.ndarray,
    meta: dict[str, str],
) -> PathData:
    seg = read_segmented(path)
    at = hold(seg.t_ns, scan_t)
    names, goals = [], []
    for s in seg.segments:
        g = _goal_name(s.goal)
        names.append(f"{s.index}: to {g}" if g else f"{s.index}: no goal reached")
        if g is not None:
            i = int(np.clip(np.searchsorted(scan_t, seg.t_ns[s.stop - 1]), 0, len(scan_t) - 1))
            goals.append(GoalMark(g, float(pose[i, 0]), float(pose[i, 1]), float(t_s[i])))
    index = {s.index: j for j, s in enumerate(seg.segments)}
    part = np.array([index[int(x)] for x in seg.segment_of[at]], dtype=np.int64)
    return PathData(
        "segmented", src, world, t_s, pose, part, tuple(names), seg.bac[at], tuple(goals), hits, meta
    )


def _run(
    path: str | Path,
    src: str,
    world: World | None,
    t_s: np.ndarray,
    pose: np.ndarray,
    scan_t: np.ndarray,
    hits: np.ndarray,
    meta: dict[str, str],
) -> PathData:
    step_t: list[int] = []
    steps: list[str | None] = []
    bacs: list[int] = []
    achieved: list[tuple[int, str]] = []
    seen: set[str] = set()
    t = 0
    try:
        for _topic, _schema, t, data in iter_messages(path, topics=[lfd.NetworkStep.TOPIC]):
            step = lfd.NetworkStep.decode(data)
            step_t.append(t)
            steps.append(step.step)
            bacs.append(step.bac)
            for g in step.achieved:
                if g not in seen:
                    seen.add(g)
                    achieved.append((t, g))
    except MessageError as exc:
        raise LogError(f"{src}: a /lfd/step message at t={t} ns: {exc}") from exc
    if not step_t:
        raise LogError(f"{src}: /lfd/step has no messages")
    names = tuple(dict.fromkeys(s for s in steps if s is not None))
    at = hold(np.array(step_t, dtype=np.int64), scan_t)
    code = {n: j for j, n in enumerate(names)}
    part = np.array([code.get(steps[i], -1) if steps[i] else -1 for i in at], dtype=np.int64)
    goals = []
    for t, g in achieved:
        i = int(np.clip(np.searchsorted(scan_t, t), 0, len(scan_t) - 1))
        goals.append(GoalMark(g, float(pose[i, 0]), float(pose[i, 1]), float(t_s[i])))
    bac = np.array(bacs, dtype=np.int64)[at]
    by_net = network_ticks(path, scan_t)  # a correction (teleop --table): who drove each tick
    if by_net is not None and not by_net.all():
        names = (*names, PERSON_PART)
        part = np.where(by_net, part, len(names) - 1)
    return PathData("run", src, world, t_s, pose, part, names, bac, tuple(goals), hits, meta)
