"""``--goals``: where a real demonstration reached its goals (DESIGN §11).

A YAML list; each item is a time (seconds from the first scan: ``12.5`` or ``{t: 12.5}``) or a
position in the odometry frame (``{x: 3.0, y: -1.2}``), optionally named (``name: door``)::

    - {t: 12.5, name: door}
    - {x: 3.0, y: -1.2}

The converter turns each goal into a target ``goal_<name>`` seen at every scan from the robot's
pose (bearing and range on ``/targets``), so ``attract`` pulls toward it and segment ends a goal
segment where the robot comes within ``REACH_M`` of it. A time goal sits where the robot was at
that time.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.files import read_yaml
from lfdfuse.robot.readings import Detection

REACH_M = 0.5  # a goal counts as reached this close (written as camera_reach_m)
_NAME = re.compile(r"^[A-Za-z0-9_]+$")


@dataclass(frozen=True)
class Goal:
    """A goal of a real demo: a time (ns from the first scan) or a position (m, odometry frame)."""

    name: str
    t_offset_ns: int | None = None
    x: float | None = None
    y: float | None = None


def _number(item: dict[str, Any], key: str, where: str) -> float:
    v = item[key]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ConfigError(f"{where}: {key} must be a number, not {v!r}")
    return float(v)


def parse_goals(data: Any, *, origin: str) -> tuple[Goal, ...]:
    """Goals from parsed YAML (see the module docstring)."""
    if not isinstance(data, list) or not data:
        raise ConfigError(f"{origin}: goals must be a non-empty YAML list of times or positions")
    goals: list[Goal] = []
    for i, raw in enumerate(data):
        where = f"{origin}: goal {i + 1}"
        item: dict[str, Any] = (
            {"t": raw} if isinstance(raw, int | float) and not isinstance(raw, bool) else raw
        )
        if not isinstance(item, dict):
            raise ConfigError(f"{where}: expected a time or a mapping with t or x and y, got {raw!r}")
        unknown = set(item) - {"t", "x", "y", "name"}
        if unknown:
            raise ConfigError(f"{where}: unknown key(s) {', '.join(sorted(map(str, unknown)))}")
        name = str(item.get("name", i + 1))
        if not _NAME.match(name):
            raise ConfigError(f"{where}: name {name!r} may hold letters, digits and _ only")
        if "t" in item and not ({"x", "y"} & set(item)):
            t = _number(item, "t", where)
            if t < 0:
                raise ConfigError(f"{where}: t must be ≥ 0 (seconds from the first scan)")
            goals.append(Goal(name, t_offset_ns=round(t * 1e9)))
        elif "x" in item and "y" in item and "t" not in item:
            goals.append(Goal(name, x=_number(item, "x", where), y=_number(item, "y", where)))
        else:
            raise ConfigError(f"{where}: give either t, or x and y")
    names = [g.name for g in goals]
    if len(set(names)) != len(names):
        raise ConfigError(f"{origin}: goal names repeat ({', '.join(names)})")
    return tuple(goals)


def read_goals(path: str | Path) -> tuple[Goal, ...]:
    return parse_goals(read_yaml(path, what="goals file"), origin=str(path))


def _hold(src_t: np.ndarray, dst_t: np.ndarray) -> np.ndarray:
    return np.clip(np.searchsorted(src_t, dst_t, side="right") - 1, 0, max(len(src_t) - 1, 0))


def goal_detections(
    goals: tuple[Goal, ...], scan_t: np.ndarray, pose_t: np.ndarray, pose: np.ndarray
) -> list[tuple[Detection, ...]]:
    """Each goal as a target seen from the robot at every scan: ``(N,)`` tuples of detections.

    ``scan_t (N,)`` and ``pose_t (P,)`` int64 ns, sorted; ``pose (P, 3)`` x, y, yaw in the odometry
    frame, held to each scan time. A time goal is placed where the robot was at that time.
    """
    if len(pose_t) == 0:
        raise ConfigError("--goals needs the robot's pose, and this log has no odometry")
    where: list[tuple[str, float, float]] = []
    for g in goals:
        if g.t_offset_ns is not None:
            t = int(scan_t[0]) + g.t_offset_ns
            if t > int(scan_t[-1]):
                raise ConfigError(f"goal {g.name}: t is past the end of the log")
            k = int(_hold(pose_t, np.array([t], dtype=np.int64))[0])
            where.append((f"goal_{g.name}", float(pose[k, 0]), float(pose[k, 1])))
        else:
            assert g.x is not None and g.y is not None
            where.append((f"goal_{g.name}", g.x, g.y))
    robot = pose[_hold(pose_t, scan_t)]
    out: list[tuple[Detection, ...]] = []
    for x, y, th in robot.tolist():
        dets = []
        for name, gx, gy in where:
            b = math.atan2(gy - y, gx - x) - th
            dets.append(Detection(name, math.atan2(math.sin(b), math.cos(b)), math.hypot(gx - x, gy - y)))
        out.append(tuple(dets))
    return out
