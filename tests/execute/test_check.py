"""The check in the demo's world: the teacher's path followed in order, the first point missed."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from lfdfuse.execute.check import RADIUS_M, SPACING_M, demo_world, follow, path_points
from lfdfuse.log.reader import read_run
from lfdfuse.robot.readings import ScanGeometry
from tests.conftest import ROOT

GEOM = ScanGeometry(-math.pi / 2, math.pi / 2, 3, 8.0)


def _path(seed: int, n: int = 400) -> np.ndarray:
    """A smooth wandering path at 4 cm per step (a robot at 0.4 m/s, 10 Hz)."""
    rng = np.random.default_rng(seed)
    heading = np.cumsum(rng.normal(0.0, 0.05, n))
    steps = 0.04 * np.stack([np.cos(heading), np.sin(heading)], axis=1)
    return np.cumsum(steps, axis=0)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_points_are_spaced_along_the_path(seed: int) -> None:
    xy = _path(seed)
    pts = path_points(xy)
    assert pts[0] == 0 and np.all(np.diff(pts) > 0) and pts[-1] < len(xy)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    assert np.all(np.diff(s[pts]) >= SPACING_M - 0.05) and np.all(np.diff(s[pts]) <= SPACING_M + 0.05)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, 0.9 * RADIUS_M), st.floats(0.2, 0.9))
def test_the_teacher_is_followed_by_itself_by_a_shifted_copy_and_not_past_where_the_robot_stopped(
    seed: int, shift: float, stop: float
) -> None:
    xy = _path(seed)
    n = len(path_points(xy))
    assert follow(xy, xy)[:2] == (n, None)
    assert follow(xy, xy + [0.0, shift])[:2] == (n, None)  # a robot a little to the side follows
    k = int(stop * len(xy))
    met, missed, last = follow(xy, xy[:k])
    pts = path_points(xy)
    assert missed is not None and missed > k - 1 and last <= missed
    assert met == int(np.searchsorted(pts, missed))  # every point before the first missed was met
    # beyond the radius, the robot is far from the first point after it stopped
    assert np.hypot(*(xy[k - 1] - xy[missed])) >= RADIUS_M - 0.05


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_order_matters_a_path_driven_backwards_is_not_followed(seed: int) -> None:
    xy = _path(seed)
    if np.hypot(*(xy[-1] - xy[0])) < 4 * RADIUS_M:
        assume(False)  # a path that comes back to its start: driven backwards it passes the start again
    met, missed, _ = follow(xy, xy[::-1])
    assert missed is not None and met < len(path_points(xy)) // 2


def test_only_a_demo_lfdfuse_drove_has_a_world_to_check_in(tmp_path: Path) -> None:
    raw = read_run(ROOT / "sample_logs" / "keep-left-building.mcap")
    home = demo_world(raw, goals=0)
    assert home is not None and home.world.name == "building"
    assert home.start.as_tuple() == pytest.approx(tuple(float(v) for v in raw.metadata["start"].split(",")))
    assert home.max_time_s >= 1.5 * home.duration_s
    assert demo_world(replace(raw, world_yaml=None), goals=0) is None
    assert demo_world(replace(raw, metadata={**raw.metadata, "command": "import"}), goals=0) is None
    assert demo_world(replace(raw, world_yaml="walls: [oops"), goals=0) is None
