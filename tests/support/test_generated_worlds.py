"""Generated off-route worlds: seeded, valid, and varied as the spec says."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import yaml

from lfdfuse.world.model import load_world
from lfdfuse.world.parse import parse_world
from tests.conftest import ROOT
from tests.support.generated_worlds import (
    HELD_APART_SEEDS,
    TUNING_SEEDS,
    generate_offroute,
    leg_point,
    offroute_spec,
    offroute_world,
)

SAMPLE = [*range(0, 40), *range(1000, 1040)]


def test_tuning_and_held_apart_seeds_do_not_overlap() -> None:
    assert not set(TUNING_SEEDS) & set(HELD_APART_SEEDS)


def test_the_same_seed_gives_the_same_world_and_another_seed_another() -> None:
    assert offroute_world(offroute_spec(7)) == offroute_world(offroute_spec(7))
    assert offroute_spec(7) != offroute_spec(8)


def test_generated_worlds_are_valid_worlds_with_the_task_targets_in_free_space() -> None:
    for seed in SAMPLE:
        w = generate_offroute(seed)
        assert w.name == f"offroute-{seed}" and len(w.walls) == 2, seed  # the ring: outer and inner wall
        assert w.target_names == ["red", "green", "blue"]
        for t in w.targets:
            assert w.clearance(t.x, t.y) >= 0.5, (seed, t)
        assert w.clearance(w.start[0], w.start[1]) >= 0.75, seed  # room for ±0.5 m perturbed starts
        again = parse_world(yaml.safe_load(w.source), origin="again")
        assert again.walls == w.walls and again.targets == w.targets


def test_green_is_at_the_end_of_the_spur_and_red_ahead_of_the_start() -> None:
    for seed in SAMPLE:
        spec = offroute_spec(seed)
        w = generate_offroute(seed)
        green = w.target("green")
        side = 1.0 if spec.spur.side == "left" else -1.0
        mouth = leg_point(spec.spur.leg, spec.spur.at_m, side * spec.width_m / 2, spec.size_m, spec.width_m)
        depth = abs(green.x - mouth[0]) + abs(green.y - mouth[1])
        assert abs(depth - (spec.spur.length_m - 0.8)) < 0.02, seed
        assert spec.red_at_m - spec.start_at_m >= 5.0 and w.target("red").x > w.start[0]


def test_the_parameters_vary_over_the_seeds() -> None:
    specs = [offroute_spec(s) for s in SAMPLE]
    assert {s.spur.side for s in specs} == {"left", "right"}
    assert {s.spur.leg for s in specs} == {"east", "north"}
    assert {len(s.decoys) for s in specs} == {0, 1, 2, 3}
    widths = [s.width_m for s in specs]
    lengths = [s.spur.length_m for s in specs]
    assert min(widths) < 2.2 and max(widths) > 2.6
    assert min(lengths) < 5.0 and max(lengths) > 8.0


def test_a_generated_world_prints_as_a_world_file_simulate_takes(tmp_path: Path) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "tests.support.generated_worlds", "1003"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    path = tmp_path / "w.yaml"
    path.write_text(out.stdout)
    world, want = load_world(str(path)), generate_offroute(1003)
    assert world.walls == want.walls and world.targets == want.targets and world.start == want.start
    bad = subprocess.run(
        [sys.executable, "-m", "tests.support.generated_worlds", "x"],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1
