"""ROS bags' laser mounting: a planar transform's matrix gives back its offset, yaw and flip."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from lfdfuse.sources.importers.records import SourceError
from lfdfuse.sources.importers.rosbag import _frame, _matrix, _yaw, mount_of

yaws = st.floats(-math.pi + 1e-6, math.pi - 1e-6)
offsets = st.floats(-2.0, 2.0)


def _transform(x: float, y: float, z: float, rot: Rotation) -> SimpleNamespace:
    qx, qy, qz, qw = rot.as_quat()
    return SimpleNamespace(
        translation=SimpleNamespace(x=x, y=y, z=z), rotation=SimpleNamespace(x=qx, y=qy, z=qz, w=qw)
    )


@given(offsets, offsets, offsets, yaws, st.booleans())
def test_a_planar_mount_round_trips(x: float, y: float, z: float, yaw: float, flipped: bool) -> None:
    rot = Rotation.from_euler("ZYX", [yaw, 0.0, math.pi if flipped else 0.0])
    m = _matrix(_transform(x, y, z, rot))
    np.testing.assert_allclose(m[:3, :3], rot.as_matrix(), atol=1e-12)
    mount = mount_of(m)
    assert mount.flipped == flipped
    assert math.isclose(mount.x_m, x, abs_tol=1e-12) and math.isclose(mount.y_m, y, abs_tol=1e-12)
    assert abs(math.atan2(math.sin(mount.yaw_rad - yaw), math.cos(mount.yaw_rad - yaw))) < 1e-9


@given(yaws)
def test_yaw_of_a_quaternion(yaw: float) -> None:
    qx, qy, qz, qw = Rotation.from_euler("z", yaw).as_quat()
    assert math.isclose(_yaw(SimpleNamespace(x=qx, y=qy, z=qz, w=qw)), yaw, abs_tol=1e-9)


@pytest.mark.parametrize("tilt_deg", [30.0, 90.0, 150.0])
def test_a_tilted_scanner_is_refused(tilt_deg: float) -> None:
    m = _matrix(_transform(0, 0, 0, Rotation.from_euler("Y", math.radians(tilt_deg))))
    with pytest.raises(SourceError, match="tilted"):
        mount_of(m)


def test_ros1_frames_lose_their_leading_slash() -> None:
    assert _frame("/base_link") == _frame("base_link") == "base_link"
