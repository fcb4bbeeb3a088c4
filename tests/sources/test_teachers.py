"""Scripted teachers: they reach their targets without collision and their style is real."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from lfdfuse.errors import ConfigError
from lfdfuse.sim.loop import RunSummary
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import STYLES, Leg, parse_task
from lfdfuse.world.model import load_world


def _run(tmp_path: Path, world: str, legs: list[Leg], seed: int, duration: float = 300.0) -> RunSummary:
    opts = SimulateOptions(
        world=load_world(world), legs=legs, teacher_name="t", duration_s=duration, seed=seed
    )
    return simulate(opts, out=tmp_path / f"{world}-{seed}.mcap")


@pytest.mark.parametrize("style", STYLES)
def test_every_style_reaches_every_building_target(tmp_path: Path, style: str) -> None:
    for k, target in enumerate(["red", "green", "blue"]):
        s = _run(tmp_path, "building", [Leg(target, style)], seed=11 + k)
        assert s.completed, f"{style} did not reach {target}"
        assert s.collisions == 0
        assert s.duration_s < 250.0  # the loop is 140 m around: about 100 s at cruise speed


def test_three_goal_task_completes_in_order(tmp_path: Path) -> None:
    for seed in (1, 2):
        legs = [Leg("red", "keep-left"), Leg("green", "keep-center"), Leg("blue", "keep-right")]
        s = _run(tmp_path, "building", legs, seed=seed, duration=500)
        assert s.completed and s.collisions == 0
        assert [n for n, _ in s.reached] == ["red", "green", "blue"]


@pytest.mark.parametrize("world", ["building", "corridor"])
def test_lateral_styles_are_real(tmp_path: Path, world: str) -> None:
    for seed in (3, 4):
        left = _run(tmp_path, world, [Leg(None, "keep-left")], seed, duration=120)
        right = _run(tmp_path, world, [Leg(None, "keep-right")], seed, duration=120)
        centre = _run(tmp_path, world, [Leg(None, "keep-center")], seed, duration=120)

        # median of the ±90° beams where both walls are in sight (corridor stretches)
        def ratio(s: RunSummary) -> float:
            both = (s.left_m < 2.5) & (s.right_m < 2.5)
            return float(np.median(s.left_m[both]) / np.median(s.right_m[both]))

        assert left.left_range_mean_m < 0.75 * left.right_range_mean_m
        assert right.right_range_mean_m < 0.75 * right.left_range_mean_m
        assert ratio(left) < 0.6 and ratio(right) > 1.6
        assert 0.8 < ratio(centre) < 1.25
        for s in (left, right, centre):
            assert s.collisions == 0


def _passing_sides(s: RunSummary, obstacles: list[tuple[float, float]]) -> list[str]:
    """For each time the robot passes an obstacle, which side the robot went by."""
    sides = []
    p = s.poses
    for ox, oy in obstacles:
        rel = p[:, 0] - ox
        for k in np.nonzero(np.sign(rel[:-1]) != np.sign(rel[1:]))[0]:
            hx, hy = math.cos(p[k, 2]), math.sin(p[k, 2])
            cross = hx * (p[k, 1] - oy) - hy * (p[k, 0] - ox)  # > 0: robot to the left of the obstacle
            sides.append("left" if cross > 0 else "right")
    return sides


@pytest.mark.parametrize("style", ["pass-left", "pass-right"])
def test_pass_styles_pass_every_obstacle_on_their_side(tmp_path: Path, style: str) -> None:
    world = load_world("obstacles")
    centres = [(ob.circle[0], ob.circle[1]) for ob in world.obstacles if ob.circle]
    for seed in (1, 2, 3):
        s = _run(tmp_path, "obstacles", [Leg(None, style)], seed, duration=110)
        sides = _passing_sides(s, centres)
        assert len(sides) >= 6  # out and back past all three
        assert set(sides) == {style.split("-")[1]}
        assert s.collisions == 0


def test_task_file_errors() -> None:
    with pytest.raises(ConfigError, match="unknown teacher style 'zigzag'"):
        parse_task({"task": [{"target": "red", "style": "zigzag"}]}, origin="t.yaml")
    with pytest.raises(ConfigError, match="unknown key 'speed'"):
        parse_task({"task": [{"target": "red", "style": "keep-left", "speed": 1}]}, origin="t.yaml")
    with pytest.raises(ConfigError, match="one key 'task'"):
        parse_task({"tasks": []}, origin="t.yaml")
