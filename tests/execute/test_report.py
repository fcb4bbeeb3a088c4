"""The execute report: each reach counts for one goal, in order; style mirrors; the file round-trips."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.execute.report import build_report, corridor_style, verdict, write_report
from lfdfuse.sim.loop import RunSummary

targets = st.sampled_from(["red", "green", "blue"])
ranges = st.lists(st.tuples(st.floats(0.1, 8.0), st.floats(0.1, 8.0)), min_size=1, max_size=40)


def _summary(reached: list[tuple[str, float]], completed: bool = False) -> RunSummary:
    return RunSummary(
        steps=100,
        duration_s=9.9,
        distance_m=3.21,
        collisions=2,
        reached=tuple(reached),
        completed=completed,
        out="x.mcap",
        left_range_mean_m=1.0,
        right_range_mean_m=1.5,
    )


@given(st.lists(targets, max_size=6), st.lists(targets, max_size=8))
def test_every_reach_counts_for_at_most_one_goal_in_order(
    goal_targets: list[str], reached: list[str]
) -> None:
    events = [(t, float(i)) for i, t in enumerate(reached)]
    goals = [(f"step{i}", t) for i, t in enumerate(goal_targets)]
    rep = build_report(_summary(events), goals=goals, side={}, unseen_ticks=0, reflex_ticks=0)
    assert [g["target"] for g in rep["goals"]] == goal_targets
    for target in set(goal_targets):
        rows = [g for g in rep["goals"] if g["target"] == target]
        hits = [t for name, t in events if name == target]
        # the k-th goal on a target takes the k-th time it was reached, if any
        assert [g["time_s"] for g in rows] == [hits[k] if k < len(hits) else None for k in range(len(rows))]
        assert all(g["reached"] == (g["time_s"] is not None) for g in rows)
    assert rep["completed"] is (False if goals else None)


@settings(max_examples=40)
@given(ranges)
def test_style_mirrors_and_ignores_ticks_without_both_walls(pairs: list[tuple[float, float]]) -> None:
    a = np.array(pairs)
    left, right = a[:, 0], a[:, 1]
    mirror = {"left": "right", "right": "left", "centre": "centre", "unknown": "unknown"}
    style = corridor_style(left, right)
    assert corridor_style(right, left) == mirror[style]
    # an opening (a wall out of sight) on some ticks changes nothing
    assert corridor_style(np.append(left, 9.0), np.append(right, 0.5)) == style
    if not ((left < 2.0) & (right < 2.0)).any():
        assert style == "unknown"


def test_a_robot_near_its_left_wall_keeps_left() -> None:
    assert corridor_style(np.full(5, 0.6), np.full(5, 1.6)) == "left"
    assert corridor_style(np.full(5, 1.0), np.full(5, 1.2)) == "centre"


@settings(max_examples=40)
@given(
    st.dictionaries(st.sampled_from(["a", "b", "c"]), ranges, max_size=3),
    st.integers(0, 50),
    st.integers(0, 50),
)
def test_step_rows_and_fractions(
    side: dict[str, list[tuple[float, float]]], unseen: int, reflex: int
) -> None:
    total = sum(len(v) for v in side.values())
    unseen, reflex = min(unseen, total), min(reflex, total)
    rep = build_report(_summary([]), goals=[], side=side, unseen_ticks=unseen, reflex_ticks=reflex)
    assert [s["name"] for s in rep["steps"]] == list(side)
    assert [s["ticks"] for s in rep["steps"]] == [len(v) for v in side.values()]
    assert 0.0 <= rep["unseen_bac_fraction"] <= 1.0 and 0.0 <= rep["reflex_fraction"] <= 1.0
    line = verdict(rep)
    assert line.endswith("2 collisions") and "task" not in line  # no goals: nothing to complete
    assert ("no step ran" in line) == (not side)


def test_the_report_file_round_trips_and_the_verdict_counts_goals(tmp_path: Path) -> None:
    rep = build_report(
        _summary([("red", 1.234), ("blue", 5.0)], completed=False),
        goals=[("reach-red", "red"), ("reach-green", "green"), ("reach-blue", "blue")],
        side={"reach-red": [(0.6, 1.6)] * 3},
        unseen_ticks=1,
        reflex_ticks=0,
    )
    path = tmp_path / "report.json"
    write_report(rep, path)
    assert json.loads(path.read_text()) == rep
    assert rep["goals"][0]["time_s"] == 1.23 and not rep["goals"][1]["reached"]
    assert verdict(rep) == (
        "task NOT completed (2/3 goals), step reach-red keeps the wall on its left, 2 collisions"
    )


def test_help_requests_extend_the_report_and_read_as_one_line() -> None:
    from lfdfuse.execute.report import help_line
    from lfdfuse.network.stepper import HelpRequest

    asks = [HelpRequest(k * 1_300_000_000, "reach-red", 5 + k, "unseen BAC") for k in range(5)]
    rep = build_report(_summary([]), goals=[], side={}, unseen_ticks=0, reflex_ticks=0, help=asks)
    assert rep["help"][1] == {"t_s": 1.3, "step": "reach-red", "bac": 6, "why": "unseen BAC"}
    assert json.loads(json.dumps(rep)) == rep
    line = help_line(rep)
    assert line is not None and line.startswith(
        "asked for help 5 times: step reach-red at 0.0 s (BAC 5: unseen BAC)"
    )
    assert line.endswith("and 2 more")
    quiet = build_report(_summary([]), goals=[], side={}, unseen_ticks=0, reflex_ticks=0)
    assert quiet["help"] == [] and help_line(quiet) is None
    assert help_line({k: v for k, v in quiet.items() if k != "help"}) is None  # a report from before


def test_the_verdict_names_each_style_once() -> None:
    steps = [
        {"name": n, "style": s} for n, s in [("a", "left"), ("b", "unknown"), ("c", "unknown"), ("d", "left")]
    ]
    rep = {"goals": [], "completed": None, "steps": steps, "collisions": 0}
    assert verdict(rep) == (
        "step a keeps the wall on its left; steps b, c have no measured style; step d keeps the wall on its left,"
        " 0 collisions"
    )
