"""``execute --starts``: perturbed starts within bounds and clear of walls, a rate that counts its
runs, a Wilson interval that behaves, the single-run report untouched without --starts."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.errors import ConfigError, LfdError
from lfdfuse.execute.starts import (
    SPREAD_M,
    SPREAD_RAD,
    StartsOptions,
    perturbed_starts,
    read_starts,
    run_starts,
    wilson_interval,
)
from lfdfuse.parallel import InProcess
from lfdfuse.robot.pose import Pose
from lfdfuse.world.model import check_pose_free, load_world
from tests.parallel.conftest import CORRIDOR_TABLE


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 500), st.integers(0, 500))
def test_wilson_interval_holds_the_rate_and_is_symmetric(k: int, n: int) -> None:
    k = min(k, n)
    lo, hi = wilson_interval(k, n)
    assert 0.0 <= lo <= hi <= 1.0
    if n:
        assert lo - 1e-12 <= k / n <= hi + 1e-12
        lo2, hi2 = wilson_interval(n - k, n)
        assert math.isclose(lo, 1 - hi2, abs_tol=1e-12) and math.isclose(hi, 1 - lo2, abs_tol=1e-12)
        if n >= 2:  # more runs, the same rate: a narrower interval
            lo4, hi4 = wilson_interval(4 * k, 4 * n)
            assert hi4 - lo4 < hi - lo


@pytest.mark.parametrize("seed", range(5))
def test_perturbed_starts_stay_within_bounds_clear_and_seeded(seed: int) -> None:
    world = load_world("corridor")
    base = Pose(*world.start)
    poses = perturbed_starts(world, base, n=20, rng=np.random.default_rng(seed))
    assert poses == perturbed_starts(world, base, n=20, rng=np.random.default_rng(seed))
    assert len(set(poses)) == 20
    for p in poses:
        assert abs(p.x - base.x) <= SPREAD_M + 1e-4 and abs(p.y - base.y) <= SPREAD_M + 1e-4
        dth = math.atan2(math.sin(p.theta - base.theta), math.cos(p.theta - base.theta))
        assert abs(dth) <= SPREAD_RAD + 1e-4
        check_pose_free(world, p.as_tuple(), what="start")


def test_a_start_in_a_wall_or_a_bad_file_is_one_error(tmp_path: Path) -> None:
    world = load_world("corridor")
    with pytest.raises(LfdError, match="start"):
        perturbed_starts(world, Pose(-5.0, 0.0, 0.0), n=3, rng=np.random.default_rng(0))
    for text in ("[]", "[[1, 2]]", "- [1, 2, .nan]", "{a: 1}", "['1,2']", "[[1, 2, true]]"):
        f = tmp_path / "starts.yaml"
        f.write_text(text)
        with pytest.raises(ConfigError):
            read_starts(f)


def test_the_rate_counts_completed_runs(goal_table: Path, tmp_path: Path) -> None:
    """Two starts beside the red target complete, one far away cannot within 4 s."""
    starts = tmp_path / "starts.yaml"
    starts.write_text("- [20.0, 7.0, 1.5708]\n- '20.0,9.0,-1.5708'\n- [4.0, 1.2, 0.0]\n")
    opts = StartsOptions(table=goal_table, world="building", starts=starts, max_time_s=4.0, seed=3)
    res = run_starts(opts, executor=InProcess()).result()
    assert [r["completed"] for r in res.runs] == [True, True, False]
    assert res.completed == 2 and res.ran == 3 and res.rate == pytest.approx(2 / 3)
    assert res.ci95 == wilson_interval(2, 3)
    assert [r["seed"] for r in res.runs] == [3, 4, 5]


def test_cli_starts_report_is_reproducible_and_the_single_report_unchanged(tmp_path: Path) -> None:
    args = ["execute", str(CORRIDOR_TABLE), "--world", "corridor", "--max-time", "3", "--seed", "7"]
    r1, r2 = tmp_path / "a.json", tmp_path / "b.json"
    for rep in (r1, r2):
        res = CliRunner().invoke(app, [*args, "--starts", "3", "--report", str(rep)])
        assert res.exit_code == 0, res.output
    assert r1.read_bytes() == r2.read_bytes()
    data = json.loads(r1.read_text())
    assert len(data["starts"]) == data["runs"] == 3 and data["failed"] == 0
    assert data["completed"] is None and data["rate"] is None  # no goals: nothing to complete
    assert "no goals" in res.output
    single = tmp_path / "single.json"
    res = CliRunner().invoke(
        app, [*args, "-o", str(tmp_path / "run.mcap"), "--report", str(single), "--start", "1,1.2,0"]
    )
    assert res.exit_code == 0, res.output
    one = json.loads(single.read_text())
    assert "starts" not in one and set(one) <= set(data["starts"][0])


@pytest.mark.parametrize(
    "extra", [["--workers", "2"], ["--starts", "2", "--workers", "2", "--scheduler", "tcp://h:8786"]]
)
def test_cli_executor_options_without_starts_or_both_are_usage_errors(extra: list[str]) -> None:
    res = CliRunner().invoke(app, ["execute", str(CORRIDOR_TABLE), "--world", "corridor", *extra])
    assert res.exit_code == 2, res.output
