"""The ROS 2 messages ``drive --ros2`` and ``record --ros2`` exchange, as DDS IDL structs.

Written once from the ``.msg`` definitions (``builtin_interfaces``, ``std_msgs``,
``geometry_msgs``, ``sensor_msgs``, ``nav_msgs``, ``tf2_msgs``) by ROS 2's ``.msg`` → IDL rules:
a message ``pkg/msg/Name`` is the struct ``pkg::msg::dds_::Name_`` (the type name a ROS 2 node
announces on the wire), ``float32``/``float64`` are ``float``/``double``, ``T[]`` a sequence,
``T[36]`` an array; every struct is final (plain CDR, what every RMW sends). Field order and types
are the wire format: a test checks each against the CDR ``rosbags`` serialises for the same message.

:data:`TYPES` names them by their ROS name; :func:`dds_topic` and :func:`ros_type` are the name
mapping (``/scan`` → ``rt/scan``). Only the DDS transport imports this module (it pulls in
``cyclonedds``).
"""

# no `from __future__ import annotations`: cyclonedds reads the field types at run time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float32, float64, int32, sequence, uint32

if TYPE_CHECKING:  # what the binding takes and gives for these fields
    Floats = list[float]
    Covariance = list[float]
else:  # what the binding reads the wire format from (at run time)
    Floats = sequence[float32]
    Covariance = array[float64, 36]

#: ROS 2's prefix of a topic's DDS name (``/scan`` → ``rt/scan``)
TOPIC_PREFIX = "rt"


def dds_topic(ros_topic: str) -> str:
    """The DDS topic name of a ROS 2 topic.

    >>> dds_topic("/scan"), dds_topic("cmd_vel")
    ('rt/scan', 'rt/cmd_vel')
    """
    return f"{TOPIC_PREFIX}/{ros_topic.lstrip('/')}"


def ros_type(dds_type: str) -> str:
    """The ROS name of a DDS type name (what a one-line note calls it).

    >>> ros_type("sensor_msgs::msg::dds_::LaserScan_"), ros_type("MyScan")
    ('sensor_msgs/msg/LaserScan', 'MyScan')
    """
    parts = dds_type.split("::")
    if len(parts) == 4 and parts[2] == "dds_" and parts[3].endswith("_"):
        return f"{parts[0]}/{parts[1]}/{parts[3][:-1]}"
    return dds_type


# -- builtin_interfaces, std_msgs --------------------------------------------------------------


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


# -- geometry_msgs ------------------------------------------------------------------------------


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class PoseMsg(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):  # (Pose: the robot's own type)
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: PoseMsg = field(default_factory=PoseMsg)
    covariance: Covariance = field(default_factory=lambda: [0.0] * 36)


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass
class TwistStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TwistStamped_"):
    header: Header = field(default_factory=Header)
    twist: Twist = field(default_factory=Twist)


@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist = field(default_factory=Twist)
    covariance: Covariance = field(default_factory=lambda: [0.0] * 36)


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


# -- sensor_msgs, nav_msgs, tf2_msgs -------------------------------------------------------------


@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    header: Header = field(default_factory=Header)
    angle_min: float32 = 0.0
    angle_max: float32 = 0.0
    angle_increment: float32 = 0.0
    time_increment: float32 = 0.0
    scan_time: float32 = 0.0
    range_min: float32 = 0.0
    range_max: float32 = 0.0
    ranges: Floats = field(default_factory=list)
    intensities: Floats = field(default_factory=list)


@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


if TYPE_CHECKING:
    Transforms = list[TransformStamped]
else:
    Transforms = sequence[TransformStamped]


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: Transforms = field(default_factory=list)


#: the structs by their ROS 2 message name
TYPES: dict[str, type[IdlStruct]] = {
    "builtin_interfaces/msg/Time": Time,
    "std_msgs/msg/Header": Header,
    "geometry_msgs/msg/Vector3": Vector3,
    "geometry_msgs/msg/Point": Point,
    "geometry_msgs/msg/Quaternion": Quaternion,
    "geometry_msgs/msg/Pose": PoseMsg,
    "geometry_msgs/msg/PoseWithCovariance": PoseWithCovariance,
    "geometry_msgs/msg/Twist": Twist,
    "geometry_msgs/msg/TwistStamped": TwistStamped,
    "geometry_msgs/msg/TwistWithCovariance": TwistWithCovariance,
    "geometry_msgs/msg/Transform": Transform,
    "geometry_msgs/msg/TransformStamped": TransformStamped,
    "sensor_msgs/msg/LaserScan": LaserScan,
    "nav_msgs/msg/Odometry": Odometry,
    "tf2_msgs/msg/TFMessage": TFMessage,
}


def stamp(t_ns: int) -> Time:
    """A ``builtin_interfaces/Time`` of int nanoseconds (negative: zero)."""
    t_ns = max(int(t_ns), 0)
    return Time(t_ns // 1_000_000_000, t_ns % 1_000_000_000)
