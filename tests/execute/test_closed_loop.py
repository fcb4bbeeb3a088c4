"""Closed-loop quality: learned networks drive the robot; thresholds measured on real runs.

These are the paper's claims (Section V) as tests: round trip against a known table, style
transfer from one building to another with the T-junction choice, the sequenced three-goal task
from perturbed starts, and obstacle negotiation on the demonstrated side.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import orjson
import pytest

from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.evaluate.roundtrip import (
    TEACHER_NOISE_RAD,
    compare_rows,
    demonstrate,
    heading_errors,
    load_truth,
)
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.log.reader import iter_messages
from lfdfuse.network.table import FusionTable
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world


def learn(tmp: Path, world: str, style: str, *, seed: int, duration: float, name: str) -> FusionTable:
    demo = tmp / f"{name}.mcap"
    simulate(
        SimulateOptions(
            world=load_world(world),
            legs=[Leg(None, style)],
            teacher_name=style,
            duration_s=duration,
            seed=seed,
        ),
        out=demo,
    )
    segment_file(demo, out=tmp / f"{name}.seg.mcap")
    table, _, _ = estimate_run(read_segmented(tmp / f"{name}.seg.mcap"), opts=EstimateOptions(seed=seed))
    return table


def per_step_sides(run: Path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Laser ranges at +90° and −90° per tick, grouped by the active network step."""
    steps: dict[int, str] = {}
    sides: dict[int, tuple[float, float]] = {}
    for topic, _s, t, data in iter_messages(run, topics=["/lfd/step", "/scan"]):
        m = orjson.loads(data)
        if topic == "/lfd/step":
            if m["step"]:
                steps[t] = m["step"]
        else:
            r = m["ranges"]
            sides[t] = (r[-1], r[0]) if len(r) == 181 else (math.nan, math.nan)
    out: dict[str, list[tuple[float, float]]] = {}
    for t, name in steps.items():
        out.setdefault(name, []).append(sides[t])
    return {k: (np.array(v)[:, 0], np.array(v)[:, 1]) for k, v in out.items()}


def run_once(
    tmp: Path,
    table: FusionTable,
    world: str,
    start: tuple[float, float, float] | None,
    seconds: float,
    name: str,
    seed: int = 0,
) -> dict:  # type: ignore[type-arg]
    pose = Pose(*start) if start else None
    res = run_table(
        ExecuteOptions(world=load_world(world), table=table, start=pose, max_time_s=seconds, seed=seed),
        out=tmp / f"{name}.mcap",
        command="execute",
    )
    return {"report": res.report, "poses": res.summary.poses, "log": tmp / f"{name}.mcap"}


# ------------------------------------------------------------------ 1. round trip


@pytest.fixture(scope="module", params=["building-right", "tee-left"])
def round_trip(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> tuple:  # type: ignore[type-arg]
    """A hand-written sparse truth table drives the network teacher twice (train, held out)."""
    tmp = tmp_path_factory.mktemp("rt")
    truth, world = load_truth(request.param)
    train = demonstrate(truth, world, seed=11, duration_s=300, folder=tmp)
    test = demonstrate(truth, world, seed=12, duration_s=150, folder=tmp)
    learned, _, _ = estimate_run(train.run, opts=EstimateOptions())
    return truth, learned, train.run, test.run


def test_round_trip_heading_error_is_at_the_noise_floor(round_trip: tuple) -> None:  # type: ignore[type-arg]
    truth, learned, _train, test = round_trip
    learned_err = heading_errors(learned, test).mean()
    true_err = heading_errors(truth, test).mean()
    assert learned_err <= 1.05 * true_err, (learned_err, true_err)


def test_round_trip_rows_the_data_pins_are_as_close_as_a_heading_fit(round_trip: tuple) -> None:  # type: ignore[type-arg]
    """Where a least-squares heading fit pins a row (within 0.06, ≥ 200 samples), the estimate is
    as close to the truth as the fit (the bar the README states)."""
    truth, learned, train, _test = round_trip
    rows = compare_rows(truth, learned, train, noise_rad=TEACHER_NOISE_RAD, min_samples=200)
    pinned = [r for r in rows if r.fit_l1 <= 0.06]
    assert pinned, [(r.bac, r.samples, r.fit_l1) for r in rows]
    for r in pinned:
        assert r.l1 <= max(2 * r.fit_l1, r.fit_l1 + 0.03), (r.bac, r.samples, r.truth, r.estimate, r.fit)


# ------------------------------------------------------------------ 2. style transfer


@pytest.fixture(scope="module")
def tee_tables(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[FusionTable]]:
    tmp = tmp_path_factory.mktemp("tee")
    return {
        style: [
            learn(tmp, "tee", style, seed=seed, duration=300, name=f"{style}{seed}") for seed in (1, 2, 3)
        ]
        for style in ("keep-left", "keep-right")
    }


CORRIDOR_STARTS = [(10.0, 1.2, 0.0), (38.8, 20.0, -math.pi / 2), (1.2, 25.0, -math.pi / 2)]


def test_styles_learned_in_tee_hold_in_building(
    tee_tables: dict[str, list[FusionTable]], tmp_path: Path
) -> None:
    for style, tables in tee_tables.items():
        for i, table in enumerate(tables):
            for j, start in enumerate(CORRIDOR_STARTS):
                rep = run_once(tmp_path, table, "building", start, 60, f"{style}-{i}-{j}")["report"]
                left, right = rep["left_range_mean_m"], rep["right_range_mean_m"]
                assert rep["collisions"] == 0
                if style == "keep-left":
                    assert left < right, (i, start, rep)
                else:
                    assert right < left, (i, start, rep)


# heading north up the middle corridor into the T of the north corridor; east up the east corridor
# into the rotated T of the cross corridor (left or straight)
T_JUNCTION = (20.0, 20.0, math.pi / 2)
ROTATED_T = (38.8, 6.0, math.pi / 2)


def test_t_junction_choice_follows_the_style(
    tee_tables: dict[str, list[FusionTable]], tmp_path: Path
) -> None:
    for style, tables in tee_tables.items():
        for i, table in enumerate(tables):
            end = run_once(tmp_path, table, "building", T_JUNCTION, 40, f"t-{style}-{i}")["poses"][-1]
            assert end[1] > 27.6  # into the north corridor
            assert (end[0] < 18.0) if style == "keep-left" else (end[0] > 22.0), (style, end)
            end = run_once(tmp_path, table, "building", ROTATED_T, 40, f"r-{style}-{i}")["poses"][-1]
            if style == "keep-left":  # "straight or left": it goes left into the cross corridor
                assert end[0] < 36.0 and 13.8 < end[1] < 16.2, end
            else:  # a right-keeper goes straight on
                assert end[0] > 37.6 and end[1] > 17.0, end


# ------------------------------------------------------------------ 3. the sequenced task


def test_three_goal_task_from_perturbed_starts(tmp_path: Path, three_goal_table: FusionTable) -> None:
    table = three_goal_table  # the sample demo segmented and estimated with the defaults
    rng = np.random.default_rng(2026)
    complete = 0
    for k in range(10):
        start = (4.0 + rng.uniform(-1.0, 1.0), 1.2 + rng.uniform(-0.35, 0.35), rng.uniform(-0.35, 0.35))
        run = run_once(tmp_path, table, "building", start, 300, f"seq{k}", seed=k)
        rep = run["report"]
        order = [
            g["target"] for g in sorted((g for g in rep["goals"] if g["reached"]), key=lambda g: g["time_s"])
        ]
        ok = rep["completed"] and order == ["red", "green", "blue"] and rep["collisions"] == 0
        complete += ok
        if not ok:
            continue
        sides = per_step_sides(run["log"])
        lft, r = sides["reach-red"]
        assert np.median(lft) < 0.8 * np.median(r), "keep-left step"
        lft, r = sides["reach-blue"]
        assert np.median(r) < 0.8 * np.median(lft), "keep-right step"
        lft, r = sides["reach-green"]
        both = (lft < 2.0) & (r < 2.0)  # where both walls are in sight
        assert abs(float(np.median(lft[both] - r[both]))) < 0.5, "keep-centre step"
    assert complete >= 9


# ------------------------------------------------------------------ 4. obstacles


def passing_sides(poses: np.ndarray, centres: list[tuple[float, float]]) -> list[str]:
    sides = []
    for ox, oy in centres:
        rel = poses[:, 0] - ox
        for k in np.nonzero(np.sign(rel[:-1]) != np.sign(rel[1:]))[0]:
            hx, hy = math.cos(poses[k, 2]), math.sin(poses[k, 2])
            sides.append("left" if hx * (poses[k, 1] - oy) - hy * (poses[k, 0] - ox) > 0 else "right")
    return sides


@pytest.mark.parametrize("style", ["pass-left", "pass-right"])
def test_obstacles_are_passed_on_the_demonstrated_side(style: str, tmp_path: Path) -> None:
    world = load_world("obstacles")
    centres = [(ob.circle[0], ob.circle[1]) for ob in world.obstacles if ob.circle]
    for seed in (1, 2, 3):
        # two round trips past the obstacles: with one (110 s) a seed in six learned to turn back
        table = learn(tmp_path, "obstacles", style, seed=seed, duration=220, name=f"{style}{seed}")
        run = run_once(tmp_path, table, "obstacles", None, 90, f"o{style}{seed}")
        sides = passing_sides(run["poses"], centres)
        assert len(sides) >= 3 and set(sides) == {style.split("-")[1]}, sides
        assert run["report"]["collisions"] == 0
