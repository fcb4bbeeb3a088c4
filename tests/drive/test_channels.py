"""Which advertised channels drive subscribes to, by role and topic."""

from __future__ import annotations

from rosbags.typesys import Stores, get_typestore

from lfdfuse.drive.decode import Role
from lfdfuse.drive.foxglove.channels import Subscriptions
from lfdfuse.drive.foxglove.wire import ServerChannel
from lfdfuse.drive.transport import Topics

STORE = get_typestore(Stores.ROS2_HUMBLE)


def cdr(cid: int, topic: str, name: str) -> ServerChannel:
    return ServerChannel(cid, topic, "cdr", name, "ros2msg", STORE.generate_msgdef(name)[0])


def js(cid: int, topic: str, name: str) -> ServerChannel:
    return ServerChannel(cid, topic, "json", name, "jsonschema", "")


def roles(s: Subscriptions) -> dict[str, Role]:
    return {sub.topic: sub.role for sub in s.subs.values()}


def test_a_ros2_bridge() -> None:
    s = Subscriptions(Topics())
    pairs, warnings = s.advertised(
        [
            cdr(1, "/scan", "sensor_msgs/msg/LaserScan"),
            cdr(2, "/scan_filtered", "sensor_msgs/msg/LaserScan"),
            cdr(3, "/wheel/odom", "nav_msgs/msg/Odometry"),
            cdr(4, "/odom", "nav_msgs/msg/Odometry"),
            cdr(5, "/tf", "tf2_msgs/msg/TFMessage"),
            cdr(6, "/tf_static", "tf2_msgs/msg/TFMessage"),
            cdr(7, "/cmd_vel", "geometry_msgs/msg/Twist"),
            cdr(8, "/image", "sensor_msgs/msg/Image"),
        ]
    )
    assert warnings == [] and s.scan and not s.camera
    assert roles(s) == {"/scan": Role.SCAN, "/odom": Role.ODOM, "/tf": Role.TF, "/tf_static": Role.TF}
    assert sorted(c for _, c in pairs) == [1, 4, 5, 6] and len({sid for sid, _ in pairs}) == 4
    s.unadvertised((1,))
    assert not s.scan and "/scan" not in s.advertised_topics()


def test_lfdfuse_teleop_and_shadow() -> None:
    s = Subscriptions(Topics(shadow=True))
    s.advertised(
        [
            js(1, "/world", "foxglove.SceneUpdate"),
            js(2, "/scan", "foxglove.LaserScan"),
            js(3, "/pose", "foxglove.PoseInFrame"),  # no /odom: the odometry-like channel stands in
            js(4, "/tf", "foxglove.FrameTransform"),
            js(5, "/targets", "lfdfuse.TargetDetections"),
            js(6, "/cmd_vel", "geometry_msgs/Twist"),
        ]
    )
    assert roles(s) == {
        "/scan": Role.SCAN,
        "/pose": Role.ODOM,
        "/tf": Role.TF,
        "/targets": Role.TARGETS,
        "/cmd_vel": Role.CMD,
    }
    assert s.camera
    # a later advertisement neither re-subscribes nor adds a second odometry
    pairs, _ = s.advertised([js(3, "/pose", "foxglove.PoseInFrame"), js(9, "/pose2", "foxglove.PoseInFrame")])
    assert pairs == []


def test_a_schema_that_does_not_parse_is_a_warning() -> None:
    s = Subscriptions(Topics())
    bad = ServerChannel(1, "/scan", "cdr", "sensor_msgs/msg/LaserScan", "ros2msg", "not ] a [ schema")
    pairs, warnings = s.advertised([bad])
    assert pairs == [] and len(warnings) == 1 and "ros2msg schema" in warnings[0] and not s.scan
