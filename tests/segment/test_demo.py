"""The demonstrated heading: a lag is a shift of the command clock; order and gaps are handled."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.control.command import DriveParams, vector_to_command
from lfdfuse.errors import LogError
from lfdfuse.log.reader import Run
from lfdfuse.robot.readings import Detection, ScanGeometry
from lfdfuse.segment.demo import demonstrated, lag_ns_of, target_names_of

DT = 100_000_000
GEOM = ScanGeometry(-math.pi / 2, math.pi / 2, 3, 8.0)


def _run(rng: np.random.Generator, n: int, *, cmd_offset_ns: int = 0, world_yaml: str | None = None) -> Run:
    """``n`` scans at 10 Hz and one command per scan (possibly offset), forward with random turns."""
    heading = rng.uniform(-1.2, 1.2, n)
    v, w = vector_to_command(np.cos(heading), np.sin(heading), DriveParams())
    return Run(
        t_ns=np.arange(n, dtype=np.int64) * DT,
        geometry=GEOM,
        ranges_m=np.full((n, 3), 8.0),
        cmd_t_ns=np.arange(n, dtype=np.int64) * DT + cmd_offset_ns,
        cmd_v_mps=np.asarray(v, dtype=float),
        cmd_omega_rps=np.asarray(w, dtype=float),
        world_yaml=world_yaml,
    )


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 8))
def test_a_lag_is_the_same_as_issuing_the_commands_earlier(seed: int, k: int) -> None:
    run = _run(np.random.default_rng(seed), 20)
    drive = DriveParams()
    lagged, ok_lagged = demonstrated(run, drive, lag_ns=k * DT)
    shifted = _run(np.random.default_rng(seed), 20, cmd_offset_ns=-k * DT)
    direct, ok_direct = demonstrated(shifted, drive)
    assert np.array_equal(ok_lagged, ok_direct)
    np.testing.assert_allclose(lagged[ok_lagged], direct[ok_direct])
    # the lag pairs scan i with command i + k (held at the last one past the end)
    want, ok0 = demonstrated(run, drive)
    idx = np.minimum(np.arange(20) + k, 19)
    np.testing.assert_allclose(lagged[ok_lagged], want[idx][ok_lagged])
    assert ok0.all()


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_commands_out_of_order_give_the_same_demo(seed: int) -> None:
    run = _run(np.random.default_rng(seed), 15)
    perm = np.random.default_rng(seed + 1).permutation(15)
    shuffled = Run(
        t_ns=run.t_ns,
        geometry=run.geometry,
        ranges_m=run.ranges_m,
        cmd_t_ns=run.cmd_t_ns[perm],
        cmd_v_mps=run.cmd_v_mps[perm],
        cmd_omega_rps=run.cmd_omega_rps[perm],
    )
    a, oka = demonstrated(run, DriveParams())
    b, okb = demonstrated(shuffled, DriveParams())
    assert np.array_equal(oka, okb) and np.array_equal(a, b)


def test_scans_before_the_first_command_and_non_finite_commands_carry_no_heading() -> None:
    run = _run(np.random.default_rng(0), 10, cmd_offset_ns=3 * DT)
    _, ok = demonstrated(run, DriveParams())
    assert not ok[:3].any() and ok[3:].all()
    run.cmd_v_mps[5] = math.nan
    _, ok = demonstrated(run, DriveParams())
    assert not ok[8] and ok[7] and ok[9]  # scan 8 holds command 5 (offset 3)


def test_a_log_without_commands_is_an_error() -> None:
    run = _run(np.random.default_rng(0), 4)
    empty = Run(
        t_ns=run.t_ns,
        geometry=GEOM,
        ranges_m=run.ranges_m,
        cmd_t_ns=np.zeros(0, np.int64),
        cmd_v_mps=np.zeros(0),
        cmd_omega_rps=np.zeros(0),
    )
    with pytest.raises(LogError, match="no /cmd_vel"):
        demonstrated(empty, DriveParams())


@given(st.floats(-60.0, 60.0))
def test_lag_in_nanoseconds_is_exact_to_the_nanosecond(lag_s: float) -> None:
    assert abs(lag_ns_of(lag_s) - lag_s * 1e9) <= 0.5 + abs(lag_s) * 1e-6


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, 60.5, -1e9])
def test_unreasonable_lags_are_refused(bad: float) -> None:
    with pytest.raises(LogError, match="--lag"):
        lag_ns_of(bad)


def test_target_names_come_from_the_world_else_from_what_was_seen() -> None:
    rng = np.random.default_rng(0)
    yaml_text = "targets:\n  - {name: red, x: 1, y: 2}\n  - {name: blue, x: 0, y: 0}\n  - {name: red, x: 3, y: 3}\n  - {name: 'bad name!'}\n"
    assert target_names_of(_run(rng, 2, world_yaml=yaml_text)) == ["red", "blue"]
    seen = _run(rng, 3, world_yaml="{broken")
    seen.detections.extend(
        [(Detection("b", 0.0, 1.0),), (), (Detection("a", 0.1, 2.0), Detection("b", 0.0, 1.0))]
    )
    assert target_names_of(seen) == ["b", "a"]
