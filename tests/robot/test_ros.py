"""ROS into the robot's records: a planar transform's matrix gives back its offset, yaw and flip; the tf
chain from the laser up to the base; LaserScan, Odometry and Twist as ``import`` and ``drive`` read them."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from lfdfuse.errors import LfdError
from lfdfuse.robot.mount import Mount, MountError, mount_of
from lfdfuse.robot.ros import (
    frame_name,
    laser_mount,
    odometry_pose,
    on_the_robot,
    quaternion_yaw,
    scan_record,
    transform_matrix,
    twist_command,
)

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
    m = transform_matrix(_transform(x, y, z, rot))
    np.testing.assert_allclose(m[:3, :3], rot.as_matrix(), atol=1e-12)
    mount = mount_of(m)
    assert mount.flipped == flipped
    assert math.isclose(mount.x_m, x, abs_tol=1e-12) and math.isclose(mount.y_m, y, abs_tol=1e-12)
    assert abs(math.atan2(math.sin(mount.yaw_rad - yaw), math.cos(mount.yaw_rad - yaw))) < 1e-9


@given(yaws)
def test_yaw_of_a_quaternion(yaw: float) -> None:
    qx, qy, qz, qw = Rotation.from_euler("z", yaw).as_quat()
    assert math.isclose(quaternion_yaw(SimpleNamespace(x=qx, y=qy, z=qz, w=qw)), yaw, abs_tol=1e-9)


@pytest.mark.parametrize("tilt_deg", [30.0, 90.0, 150.0])
def test_a_tilted_scanner_is_refused(tilt_deg: float) -> None:
    m = transform_matrix(_transform(0, 0, 0, Rotation.from_euler("Y", math.radians(tilt_deg))))
    with pytest.raises(MountError, match="tilted"):
        mount_of(m)


def test_ros1_frames_lose_their_leading_slash() -> None:
    assert frame_name("/base_link") == frame_name("base_link") == "base_link"


def _edge(parent: str, x: float, yaw: float, *, flipped: bool = False) -> tuple[str, np.ndarray]:
    rot = Rotation.from_euler("ZYX", [yaw, 0.0, math.pi if flipped else 0.0])
    return parent, transform_matrix(_transform(x, 0.0, 0.2, rot))


def test_the_chain_composes_every_transform_from_the_laser_up_to_the_first_base() -> None:
    edges = {"laser": _edge("plate", 0.0, math.pi / 4), "plate": _edge("base_link", 0.1, math.pi / 4)}
    edges["base_link"] = _edge("base_footprint", 5.0, 1.0)  # beyond the first base: not used
    found = laser_mount(edges, "laser", ("base_link", "base_footprint"))
    assert found is not None and found.base == "base_link" and found.frames == ("laser", "plate")
    assert found.mount.x_m == pytest.approx(0.1) and found.mount.yaw_rad == pytest.approx(math.pi / 2)
    assert found.describe("/tf_static") == "/tf_static (base_link → laser)"
    upside_down = laser_mount({"laser": _edge("base_link", 0.0, 0.0, flipped=True)}, "laser", ("base_link",))
    assert upside_down is not None and upside_down.mount.flipped


def test_a_chain_that_stops_short_or_loops_gives_no_mount() -> None:
    assert laser_mount({"laser": _edge("plate", 0.0, 0.0)}, "laser", ("base_link",)) is None
    loop = {"laser": _edge("plate", 0.0, 0.0), "plate": _edge("laser", 0.0, 0.0)}
    assert laser_mount(loop, "laser", ("base_link",)) is None


def test_scans_in_the_base_frame_sit_at_the_base() -> None:
    found = laser_mount({}, "base_link", ("base_link",))
    assert found is not None and found.mount == Mount() and found.frames == ()
    assert found.describe("tf") == "the scans are in the base frame 'base_link'"


def test_world_frames_say_nothing_about_the_mounting() -> None:
    assert on_the_robot("base_link", "laser")
    assert not on_the_robot("odom", "base_link") and not on_the_robot("base_link", "map")


def test_a_tilted_scanner_is_a_user_facing_error() -> None:
    assert issubclass(MountError, LfdError)  # the CLI prints it as one ``error:`` line


def test_a_laserscan_becomes_a_record_with_no_return_as_inf() -> None:
    msg = SimpleNamespace(
        angle_min=-1.5,
        angle_increment=0.5,
        range_min=0.1,
        range_max=float(np.float32(5.6)),
        ranges=np.array([1.0, 0.05, np.nan, 7.0, 0.0, 2.5], dtype=np.float32),
    )
    rec = scan_record(msg, 42)
    assert rec.t_ns == 42 and rec.max_range_m == 5.6  # float32's 5.5999999 read as the 5.6 it was
    assert rec.start_rad == -1.5 and rec.increment_rad == 0.5 and rec.count == 6
    assert rec.ranges_m.dtype == np.float64
    assert rec.ranges_m.tolist() == [1.0, math.inf, math.inf, math.inf, math.inf, 2.5]


@given(offsets, offsets, yaws)
def test_odometry_and_twists_become_records(x: float, y: float, yaw: float) -> None:
    qx, qy, qz, qw = Rotation.from_euler("z", yaw).as_quat()
    pose = SimpleNamespace(
        position=SimpleNamespace(x=x, y=y, z=0.0), orientation=SimpleNamespace(x=qx, y=qy, z=qz, w=qw)
    )
    p = odometry_pose(SimpleNamespace(pose=SimpleNamespace(pose=pose)), 7)
    assert (p.t_ns, p.x, p.y) == (7, x, y) and math.isclose(p.theta, yaw, abs_tol=1e-9)
    twist = SimpleNamespace(
        linear=SimpleNamespace(x=x, y=0.0, z=0.0), angular=SimpleNamespace(x=0.0, y=0.0, z=yaw)
    )
    for msg in (twist, SimpleNamespace(header=None, twist=twist)):  # Twist and TwistStamped
        c = twist_command(msg, 9)
        assert (c.t_ns, c.v_mps, c.omega_rps) == (9, x, yaw)


def test_frames_with_a_leading_slash_are_the_same_frames() -> None:
    """ROS 1 drivers wrote ``/base_link``; tf2 writes ``base_link``: one frame either way."""
    tf = transform_matrix(_transform(-0.1, 0.0, 0.2, Rotation.from_euler("z", math.pi)))
    for edges, laser, bases in (
        ({"/base_laser_link": ("/base_link", tf)}, "/base_laser_link", ("base_link",)),
        ({"base_laser_link": ("/base_link", tf)}, "/base_laser_link", ("base_link",)),
        ({"/base_laser_link": ("base_link", tf)}, "base_laser_link", ("/base_link",)),
    ):
        found = laser_mount(edges, laser, bases)
        assert found is not None and found.base == "base_link" and found.frames == ("base_laser_link",)
        assert math.isclose(found.mount.x_m, -0.1, abs_tol=1e-12)
    assert laser_mount({"/laser": ("/base_link", tf)}, "/base_link", ("base_link",)) is not None
    assert not on_the_robot("/odom", "base_link") and on_the_robot("/base_link", "/laser")
