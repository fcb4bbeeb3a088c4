"""The execute report (DESIGN §8) and its one-line verdict: goals, style per step, collisions."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.files import write_text_atomic
from lfdfuse.sim.loop import RunSummary


def build_report(
    summary: RunSummary,
    *,
    goals: list[tuple[str, str]],
    side: dict[str, list[tuple[float, float]]],
    unseen_ticks: int,
    reflex_ticks: int,
) -> dict[str, Any]:
    """The report of DESIGN §8 from a run and the network's per-step side ranges.

    ``goals`` are the table's ``(step name, target)`` in order; a network without goals has
    nothing to complete (``completed: null``).
    """
    reached_at = list(summary.reached)
    goal_rows = []
    for name, target in goals:
        hit = next((i for i, (g, _) in enumerate(reached_at) if g == target), None)
        t = None if hit is None else reached_at.pop(hit)[1]
        goal_rows.append(
            {
                "name": name,
                "target": target,
                "reached": t is not None,
                "time_s": None if t is None else round(t, 2),
            }
        )
    steps = []
    for name, pairs in side.items():
        arr = np.array(pairs)
        steps.append(
            {
                "name": name,
                "left_range_mean_m": round(float(arr[:, 0].mean()), 3),
                "right_range_mean_m": round(float(arr[:, 1].mean()), 3),
                "ticks": len(pairs),
                "style": corridor_style(arr[:, 0], arr[:, 1]),
            }
        )
    active_ticks = sum(len(p) for p in side.values())
    return {
        "completed": bool(summary.completed) if goals else None,
        "duration_s": round(summary.duration_s, 2),
        "collisions": summary.collisions,
        "path_length_m": round(summary.distance_m, 2),
        "goals": goal_rows,
        "steps": steps,
        "left_range_mean_m": round(summary.left_range_mean_m, 3),
        "right_range_mean_m": round(summary.right_range_mean_m, 3),
        "unseen_bac_fraction": round(unseen_ticks / max(active_ticks, 1), 4),
        "reflex_fraction": round(reflex_ticks / max(active_ticks, 1), 4),
    }


def write_report(report: dict[str, Any], path: str | Path) -> None:
    write_text_atomic(path, json.dumps(report, indent=1) + "\n")


def corridor_style(left_m: np.ndarray, right_m: np.ndarray, *, sight_m: float = 2.0) -> str:
    """The paper's style measure (Fig. 10) in words, from the ±90° ranges of each tick.

    Only ticks with both walls in sight count (corridor stretches): a mean over openings, doors and
    crossings says more about the building than about the robot. ``left``, ``right`` or
    ``centre`` (median offset under 0.25 m); ``unknown`` without such ticks.
    """
    both = (left_m < sight_m) & (right_m < sight_m)
    if not both.any():
        return "unknown"
    offset = float(np.median(right_m[both] - left_m[both])) / 2  # > 0: the robot is left of centre
    if offset > 0.25:
        return "left"
    if offset < -0.25:
        return "right"
    return "centre"


def _style_words(step: dict[str, Any]) -> str:
    """``step free (no goal) keeps the wall on its left`` — what a step's corridor style means."""
    style = step.get("style", "unknown")
    side = {"left": "keeps the wall on its left", "right": "keeps the wall on its right"}
    words = side.get(style, "keeps to the centre" if style in ("center", "centre") else f"keeps {style}")
    return f"step {step['name']} {words}"


def verdict(report: dict[str, Any]) -> str:
    """One line: task completed (when it has goals) and the style of each step."""
    parts = []
    if report["goals"]:
        done = sum(g["reached"] for g in report["goals"])
        parts.append(
            f"task {'completed' if report['completed'] else 'NOT completed'} ({done}/{len(report['goals'])} goals)"
        )
    styles = [_style_words(s) for s in report["steps"]]
    parts.append("; ".join(styles) if styles else "no step ran")
    parts.append(f"{report['collisions']} collisions")
    return ", ".join(parts)
