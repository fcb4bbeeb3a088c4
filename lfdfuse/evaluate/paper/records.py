"""The records of the paper's experiments, and the measures read off them (pure functions).

Everything here is data: what a demonstration taught (:class:`Learned`), what a run of a learned
network did (:class:`PaperRun`), and every experiment's results together (:class:`PaperResults`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.network.table import FusionTable

#: the three corridor styles of the paper's Scenario 3
STYLES = ("keep-left", "keep-center", "keep-right")


@dataclass(frozen=True)
class Learned:
    """A demonstration and what was learned from it."""

    style: str
    world: str
    demo: Path
    segmented: Path
    table_path: Path
    table: FusionTable
    demo_left_m: float  # mean laser range at +90° over the demonstration
    demo_right_m: float
    demo_style: str
    seconds: float
    demo_pose: np.ndarray  # (N, 3) per scan of the demonstration
    demo_left: np.ndarray  # (N,) laser range at +90° per scan (m)
    demo_right: np.ndarray  # (N,) at −90°


@dataclass(frozen=True)
class PaperRun:
    """One execution of a learned network: its report, its path ``(N, 3)`` and ±90° ranges ``(N,)``."""

    label: str
    world: str
    log: Path
    report: dict[str, Any]
    pose: np.ndarray
    left_m: np.ndarray
    right_m: np.ndarray
    style: str  # the corridor style it kept (left, centre, right, unknown)

    def summary(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "world": self.world,
            "log": self.log.name,
            "style": self.style,
            **self.report,
        }


@dataclass(frozen=True)
class PaperResults:
    """Every experiment of the report.

    ``learned``: by style (``keep-left``…, ``pass-left``…), ``task`` and ``trials`` (the task
    learned over many trials). ``runs``: ``<style>/tee``, ``<style>/building``, ``junction/T``,
    ``junction/rotated T``, ``task``, ``pass-left``, ``pass-right``. ``junctions``: per style, the
    way taken at each junction. ``style_errors``: ``(label, left, right)``, the runs' distance to
    each wall minus the demonstration's (m).
    """

    seed: int
    quick: bool
    trials: int
    learned: Mapping[str, Learned]
    runs: Mapping[str, tuple[PaperRun, ...]]
    junctions: Mapping[str, Mapping[str, str]]
    style_errors: tuple[tuple[str, float, float], ...]


# ------------------------------------------------------------------------------ the measures


def junction_choice(end: np.ndarray, which: str) -> str:
    """Where a run from the T or the rotated T went: left, right, straight or none."""
    x, y = float(end[0]), float(end[1])
    if which == "T":
        if y <= 27.6:
            return "none"
        return "left" if x < 18.0 else "right" if x > 22.0 else "none"
    if x < 36.0 and 13.8 < y < 16.2:
        return "left"
    if x > 37.6 and y > 17.0:
        return "straight"
    return "none"


def passing_sides(pose: np.ndarray, centres: list[tuple[float, float]]) -> list[str]:
    """On which side of the robot each obstacle was when the path crossed the obstacle's x."""
    sides = []
    for ox, oy in centres:
        rel = pose[:, 0] - ox
        for k in np.nonzero(np.sign(rel[:-1]) != np.sign(rel[1:]))[0]:
            hx, hy = math.cos(pose[k, 2]), math.sin(pose[k, 2])
            sides.append("left" if hx * (pose[k, 1] - oy) - hy * (pose[k, 0] - ox) > 0 else "right")
    return sides


def task_order(report: dict[str, Any]) -> list[str]:
    """The targets a run reached, in the order it reached them."""
    reached = sorted((g for g in report["goals"] if g["reached"]), key=lambda g: g["time_s"])
    return [str(g["target"]) for g in reached]
