"""The clamp, the watchdog and the laser mounting: laws with injected times."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lfdfuse.drive.decode import LiveTf, Transform
from lfdfuse.drive.frames import ScanFrame, TfTree
from lfdfuse.drive.safety import Limits, Watchdog, limits_of
from lfdfuse.errors import ConfigError
from lfdfuse.robot.records import ScanRecord
from lfdfuse.robot.ros import quaternion_matrix


@given(st.floats(allow_nan=True, allow_infinity=True), st.floats(allow_nan=True, allow_infinity=True))
def test_the_clamp_never_exceeds_the_limits(v: float, w: float) -> None:
    lim = Limits(0.3, 1.2)
    cv, cw = lim.clamp(v, w)
    assert abs(cv) <= 0.3 and abs(cw) <= 1.2
    if math.isfinite(v) and math.isfinite(w) and abs(v) <= 0.3 and abs(w) <= 1.2:
        assert (cv, cw) == (v, w)


def test_limits_from_the_table_clamped_by_the_options() -> None:
    lim, whence = limits_of({"v_max_mps": 0.5, "omega_max_rps": 1.0}, max_speed=0.2, max_turn=None)
    assert lim == Limits(0.2, 1.0) and whence == "speed: --max-speed; turn: the table's robot"
    lim, whence = limits_of({"v_max_mps": 0.5, "omega_max_rps": 1.0}, max_speed=0.9, max_turn=None)
    assert lim == Limits(0.5, 1.0) and whence == "the table's robot"  # an option above the robot's: no clamp
    lim, whence = limits_of({}, max_speed=None, max_turn=None)
    assert lim.v_max_mps == 0.4 and whence == "the simulated robot's (the table does not say)"
    lim, whence = limits_of({}, max_speed=0.2, max_turn=None)  # the speed is the option's, not ours
    assert lim.v_max_mps == 0.2 and whence.startswith("speed: --max-speed; turn: the simulated robot's")
    with pytest.raises(ConfigError):
        limits_of({}, max_speed=-1.0, max_turn=None)


def test_watchdog_fresh_stale_and_blind() -> None:
    wd = Watchdog(max_age_s=0.5)
    assert wd.blind(0.0)  # nothing yet
    assert wd.scan(1_000_000_000, 10.0) == ""
    assert wd.blind(10.0)  # fresh, but not yet used for a command
    wd.commanded(10.0)
    assert not wd.blind(10.4) and wd.blind(10.51)
    assert "does not advance" in wd.scan(1_000_000_000, 10.1)
    assert wd.scan(1_100_000_000, 10.1) == ""
    # a scan that arrives 0.6 s later than scans do (a backlog) is stale, a constant offset is not
    assert "later than scans do" in wd.scan(1_200_000_000, 10.8)
    assert wd.scan(1_900_000_000, 10.9) == ""
    wd.reset()
    assert wd.blind(11.0) and wd.scan(5, 11.0) == ""  # a new connection may restart its clock


@given(st.floats(-1e6, 1e6))
def test_a_clock_offset_alone_never_makes_scans_stale(offset_s: float) -> None:
    wd = Watchdog()
    for k in range(20):
        t = 0.1 * k
        assert wd.scan(int((t + 1000.0) * 1e9), t + offset_s + 0.02 * (k % 3)) == ""


def _tf(parent: str, child: str, x: float, yaw: float, roll: float = 0.0) -> LiveTf:
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    q = (sr * cy, -sr * sy, cr * sy, cr * cy) if roll else (0.0, 0.0, sy, cy)
    m = quaternion_matrix(x, 0.0, 0.0, *q)
    return LiveTf((Transform(parent, child, tuple(tuple(float(v) for v in r) for r in m)),))


def test_mount_from_a_tf_chain_ignores_world_frames() -> None:
    tree = TfTree()
    tree.add(_tf("odom", "base_link", 5.0, 1.0))  # moves with the robot: not the mounting
    assert tree.mount("laser", ("base_link",)) is None
    tree.add(_tf("base_link", "plate", 0.1, math.pi / 4))
    tree.add(_tf("plate", "laser", 0.0, math.pi / 4))
    found = tree.mount("laser", ("base_link",))
    assert found is not None
    mount, whence = found
    assert mount.yaw_rad == pytest.approx(math.pi / 2) and mount.x_m == pytest.approx(0.1) and "tf" in whence
    assert tree.mount("base_link", ("base_link",)) is not None


@given(st.floats(-math.pi, math.pi), st.booleans())
def test_scans_turned_into_the_base_frame_keep_each_beam_bearing(yaw: float, flipped: bool) -> None:
    """A beam at sensor angle a, mounted with yaw y, points at y + a (y − a upside down)."""
    tree = TfTree()
    tree.add(_tf("base_link", "laser", 0.0, yaw, roll=math.pi if flipped else 0.0))
    found = tree.mount("laser", ("base_link",))
    assert found is not None and found[0].flipped == flipped
    n, start, inc = 9, -1.0, 0.25
    ranges = np.arange(1.0, n + 1.0)
    frame = ScanFrame.of(ScanRecord(0, start, inc, ranges, 20.0), found[0])
    base = frame.ranges(ScanRecord(1, start, inc, ranges, 20.0))
    angles = frame.geometry.angles
    for i, a in enumerate(start + inc * np.arange(n)):
        want = found[0].yaw_rad - a if flipped else found[0].yaw_rad + a
        j = int(np.argmin(np.abs(np.angle(np.exp(1j * (angles - want))))))
        assert base[j] == ranges[i]
