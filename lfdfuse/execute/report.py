"""The execute report (DESIGN §8) and its one-line verdict: goals, style per step, collisions."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.files import write_text_atomic
from lfdfuse.network.stepper import HelpRequest, NetworkStepper
from lfdfuse.network.table import FusionTable, leaf_steps
from lfdfuse.sim.loop import RunSummary
from lfdfuse.words import counted


def build_report(
    summary: RunSummary,
    *,
    goals: list[tuple[str, str]],
    side: dict[str, list[tuple[float, float]]],
    unseen_ticks: int,
    reflex_ticks: int,
    help: Sequence[HelpRequest] = (),
) -> dict[str, Any]:
    """The report of DESIGN §8 from a run and the network's per-step side ranges.

    ``goals`` are the table's ``(step name, target)`` in order; a network without goals has
    nothing to complete (``completed: null``). ``help`` (an extension: a key old readers ignore)
    lists where the network asked for help, each ``{t_s, step, bac, why}``.
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
        "help": [{"t_s": round(h.t_s, 2), "step": h.step, "bac": h.bac, "why": h.why} for h in help],
    }


def goal_list(table: FusionTable) -> list[tuple[str, str]]:
    """The table's goal steps ``(step name, target)`` in the order of its goal segments."""
    return [(s.name, s.goal) for s in leaf_steps(table) if s.goal is not None]


def network_report(summary: RunSummary, driver: NetworkStepper) -> dict[str, Any]:
    """:func:`build_report` of a run the network ``driver`` drove (execute, ``teleop --table``)."""
    return build_report(
        summary,
        goals=goal_list(driver.table),
        side=driver.side,
        unseen_ticks=driver.unseen_ticks,
        reflex_ticks=driver.reflex_ticks,
        help=driver.help,
    )


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
    """``keeps the wall on its left`` — what a step's corridor style means."""
    style = step.get("style", "unknown")
    side = {"left": "keeps the wall on its left", "right": "keeps the wall on its right"}
    if style in ("center", "centre"):
        return "keeps to the centre"
    # unknown: the step never drove with both walls within 2 m (or never ran)
    return side.get(style, f"keeps {style}" if style != "unknown" else "has no measured style")


def _styles(steps: list[dict[str, Any]]) -> list[str]:
    """Each step's style in words; consecutive steps of one style share one phrase."""
    out: list[tuple[list[str], str]] = []
    for s in steps:
        words = _style_words(s)
        if out and out[-1][1] == words:
            out[-1][0].append(s["name"])
        else:
            out.append(([s["name"]], words))
    plural = {"keeps": "keep", "has": "have"}
    return [
        f"step {n[0]} {w}"
        if len(n) == 1
        else f"steps {', '.join(n)} {plural[w.split()[0]]} {w.split(' ', 1)[1]}"
        for n, w in out
    ]


def verdict(report: dict[str, Any]) -> str:
    """One line: task completed (when it has goals) and the style of each step."""
    parts = []
    if report["goals"]:
        done = sum(g["reached"] for g in report["goals"])
        parts.append(
            f"task {'completed' if report['completed'] else 'NOT completed'} ({done}/{len(report['goals'])} goals)"
        )
    styles = _styles(report["steps"])
    parts.append("; ".join(styles) if styles else "no step ran")
    parts.append(counted(report["collisions"], "collision"))
    return ", ".join(parts)


def help_line(report: dict[str, Any], *, shown: int = 3) -> str | None:
    """Where the network asked for help, in one line (None when it never did)::

    asked for help 2 times: step reach-red at 12.3 s (BAC 5: unseen BAC), …
    """
    asks = report.get("help") or []
    if not asks:
        return None
    first = ", ".join(
        f"step {h['step']} at {h['t_s']:.1f} s (BAC {h['bac']}: {h['why']})" for h in asks[:shown]
    )
    more = f", and {len(asks) - shown} more" if len(asks) > shown else ""
    return f"asked for help {len(asks)} time{'s' if len(asks) != 1 else ''}: {first}{more}"
