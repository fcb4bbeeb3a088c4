"""Each format module for itself: ``detect`` picks exactly its own files and never raises; the
parsers' laws (time order, dead reckoning, beam geometry) on tiny hand-made files."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lfdfuse.log import messages as msg
from lfdfuse.log.writer import LogWriter
from lfdfuse.sources.importers import FORMATS, breezyslam, carmen, ros1, ros2
from lfdfuse.sources.importers.records import TopicChoice
from tests.conftest import SHARED

REAL = SHARED / "realdata"
REAL_LOGS = {
    "carmen/mit-csail.clf": "carmen",
    "carmen/intel-corrected.log.gz": "carmen",
    "carmen/freiburg-079-corrected.log.gz": "carmen",
    "breezyslam/exp2.dat": "breezyslam",
    "ros1/neato-keyboard-middle.bag": "ros1",
    "ros1/demo_stationary_simple_environment.bag": "ros1",
    "ros2/macfirst_floor_take_2.mcap": "ros2",
    "ros2/macfirst_floor_take_2": "ros2",
}


@pytest.mark.parametrize("rel", sorted(REAL_LOGS))
def test_exactly_one_format_detects_each_real_log(rel: str) -> None:
    path = REAL / rel
    if not path.exists():
        pytest.skip(f"{path} is not available")
    assert [name for name, mod in FORMATS.items() if mod.detect(path)] == [REAL_LOGS[rel]]


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.binary(max_size=300), st.sampled_from(["x.bag", "x.mcap", "x.db3", "x.clf", "x.log.gz", "x.dat"]))
def test_detect_never_raises_on_arbitrary_bytes(tmp_path: Path, data: bytes, name: str) -> None:
    path = tmp_path / name
    path.write_bytes(data)
    for mod in FORMATS.values():
        assert mod.detect(path) in (True, False)


def test_nothing_detects_a_missing_path_or_an_lfdfuse_demo(tmp_path: Path) -> None:
    demo = tmp_path / "demo.mcap"
    with LogWriter(demo, metadata={"seed": "0"}) as log:
        log.write("/cmd_vel", 0, msg.twist(0, 0.1, 0.0))
    for mod in FORMATS.values():
        assert not mod.detect(tmp_path / "missing")
    assert not ros2.detect(demo)  # JSON messages, not cdr
    assert not ros1.detect(demo) and not carmen.detect(demo) and not breezyslam.detect(demo)
    empty = tmp_path / "empty"
    empty.mkdir()
    assert not ros2.detect(empty)  # a folder without metadata.yaml, .db3 or .mcap is no bag


@given(st.integers(2, 2000))
def test_carmen_beams_span_a_half_circle_from_the_right(n: int) -> None:
    start, inc = carmen.beam_geometry(n)
    assert start == -math.pi / 2 and inc > 0
    end = start + (n - 1) * inc
    # 180 and 360 readings are 1° and 0.5° (the last beam short of +90°); others spread over 180°
    want = math.pi / 2 - (math.radians(1.0) if n == 180 else math.radians(0.5) if n == 360 else 0.0)
    assert math.isclose(end, want, abs_tol=1e-12)


def _flaser(t_s: float, x: float, ranges: list[float]) -> str:
    r = " ".join(f"{v:.3f}" for v in ranges)
    return f"FLASER {len(ranges)} {r} {x} 0 0 {x} 0 0 {t_s:.6f} host {t_s:.6f}"


@settings(max_examples=25, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.permutations(list(range(8))))
def test_carmen_serves_laser_lines_in_time_order_whatever_the_file_order(
    tmp_path: Path, order: list[int]
) -> None:
    path = tmp_path / "t.clf"
    path.write_text("\n".join(_flaser(100.0 + 0.1 * k, 0.05 * k, [1.0 + k] * 181) for k in order) + "\n")
    assert carmen.detect(path)
    src = carmen.open_source(path, topics=TopicChoice())
    scans, poses = list(src.iter_scans()), list(src.iter_poses())
    assert [s.t_ns for s in scans] == [100_000_000_000 + k * 100_000_000 for k in range(8)]
    assert [s.ranges_m[0] for s in scans] == [1.0 + k for k in range(8)]
    assert [p.x for p in poses] == [0.05 * k for k in range(8)]
    late = sum(k < max(order[:i]) for i, k in enumerate(order) if i)  # lines earlier than one before them
    assert src.info.notes == ((f"{late} FLASER lines out of time order (sorted)",) if late else ())
    assert list(src.iter_commands()) == []  # no ODOM lines: commands are derived by the converter


def _breezy(path: Path, ticks: list[tuple[int, int]]) -> None:
    rows = []
    for k, (left, right) in enumerate(ticks):
        ranges = ["1500"] * 40
        rows.append(
            " ".join([str(1_000_000 + 100_000 * k), "0", str(left), str(right), *["7"] * 20, *ranges, "9"])
        )
    path.write_text("\n".join(rows) + "\n")


@settings(max_examples=40)
@given(st.lists(st.integers(-300, 300), min_size=1, max_size=15))
def test_breezyslam_equal_ticks_drive_straight_and_opposite_ticks_turn_on_the_spot(steps: list[int]) -> None:
    with tempfile.TemporaryDirectory() as d:
        straight, spin = Path(d) / "s.dat", Path(d) / "t.dat"
        cum = np.concatenate([[0], np.cumsum(steps)]).tolist()
        _breezy(straight, [(c, c) for c in cum])
        _breezy(spin, [(-c, c) for c in cum])
        assert breezyslam.detect(straight) and breezyslam.detect(spin)
        rover = breezyslam.Rover()
        per_tick = 2 * math.pi * rover.wheel_radius_m / rover.ticks_per_rev
        s = list(breezyslam.open_source(straight, topics=TopicChoice()).iter_poses())
        np.testing.assert_allclose([p.x for p in s], np.array(cum) * per_tick, atol=1e-9)
        assert all(p.y == 0.0 and p.theta == 0.0 for p in s)
        t = list(breezyslam.open_source(spin, topics=TopicChoice()).iter_poses())
        assert all(abs(p.x) < 1e-12 and abs(p.y) < 1e-12 for p in t)
        want = np.array(cum) * per_tick / rover.half_axle_m
        np.testing.assert_allclose(
            np.cos([p.theta for p in t]) + 1j * np.sin([p.theta for p in t]), np.exp(1j * want), atol=1e-9
        )
