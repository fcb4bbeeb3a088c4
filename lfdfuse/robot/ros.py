"""ROS messages into the robot's own records: frames, quaternions, tf, LaserScan, Odometry, Twist.

The one conversion ``import`` (ROS 1 and ROS 2 bags) and ``drive`` (a ``foxglove_bridge``'s
CDR) share. Messages are read by attribute, the way ``rosbags`` deserialises them
(``msg.header.frame_id``, ``q.w``), so nothing here needs ROS or ``rosbags`` itself.

Where the laser sits comes from tf: the chain of transforms from the scan's frame up to the
robot's base frame (the odometry's child frame, else ``base_link`` / ``base_footprint``).
Transforms from a world frame (``odom``, ``map``) move with the robot and say nothing about
the mounting.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from lfdfuse.robot.mount import Mount, mount_of
from lfdfuse.robot.records import CommandRecord, PoseRecord, ScanRecord, no_return

BASE_FRAMES = ("base_link", "base_footprint")
WORLD_FRAMES = ("odom", "map", "world", "earth")


def frame_name(name: str) -> str:
    """A frame id without the leading slash ROS 1 frames may carry (``/base_link`` and
    ``base_link`` are one frame); every comparison of frames here goes through it.

    >>> frame_name("/base_laser_link"), frame_name("odom")
    ('base_laser_link', 'odom')
    """
    return name.lstrip("/")


def header_ns(header: Any) -> int:
    """A ``std_msgs/Header``'s stamp in int nanoseconds."""
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def quaternion_yaw(q: Any) -> float:
    """The yaw (rad) of a quaternion with fields ``x, y, z, w``."""
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def quaternion_matrix(
    tx: float, ty: float, tz: float, qx: float, qy: float, qz: float, qw: float
) -> np.ndarray:
    """A translation and a unit quaternion as a 4×4 homogeneous matrix."""
    x, y, z, w = qx, qy, qz, qw
    m = np.eye(4)
    m[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    m[:3, 3] = [tx, ty, tz]
    return m


def transform_matrix(tr: Any) -> np.ndarray:
    """A ``geometry_msgs/Transform`` as a 4×4 homogeneous matrix."""
    t, q = tr.translation, tr.rotation
    return quaternion_matrix(t.x, t.y, t.z, q.x, q.y, q.z, q.w)


def on_the_robot(parent: str, child: str) -> bool:
    """Whether a transform can be part of the laser's mounting (neither end is a world frame).

    >>> on_the_robot("/odom", "/base_link"), on_the_robot("/base_link", "laser")
    (False, True)
    """
    return frame_name(parent) not in WORLD_FRAMES and frame_name(child) not in WORLD_FRAMES


@dataclass(frozen=True)
class LaserMount:
    """Where the laser sits, as tf says: the mounting, the base frame reached, and the child
    frames of the transforms used from the laser up (none: the scans are in the base frame)."""

    mount: Mount
    base: str
    frames: tuple[str, ...]

    def describe(self, via: str) -> str:
        """How the mounting was found; ``via`` names where the transforms came from."""
        if not self.frames:
            return f"the scans are in the base frame {self.base!r}"
        return f"{via} ({self.base} → {self.frames[0]})"


def laser_mount(
    edges: Mapping[str, tuple[str, np.ndarray]], laser: str, bases: Sequence[str]
) -> LaserMount | None:
    """The mounting of the laser in frame ``laser``: the chain of ``edges`` (child → (parent,
    4×4 transform)) from it up to the first of ``bases`` it reaches. None when the chain does not
    reach a base frame (or loops, in a malformed tree); a tilted scanner is a
    :class:`~lfdfuse.robot.mount.MountError`. Frame names are compared without a leading slash."""
    edges = {frame_name(c): (frame_name(p), tf) for c, (p, tf) in edges.items()}
    laser, bases = frame_name(laser), tuple(frame_name(b) for b in bases)
    if laser in bases:
        return LaserMount(Mount(), laser, ())
    frame, m, passed = laser, np.eye(4), [laser]
    while frame not in bases and frame in edges:
        parent, tf = edges[frame]
        m, frame = tf @ m, parent
        if frame in passed:
            return None
        passed.append(frame)
    if frame not in bases:
        return None
    return LaserMount(mount_of(m), frame, tuple(passed[:-1]))


def scan_record(msg: Any, t_ns: int) -> ScanRecord:
    """A ``sensor_msgs/LaserScan`` stamped ``t_ns``, every beam without a return set to ``inf``."""
    max_m = round(float(msg.range_max), 6)  # float32 in the message: 5.6, not 5.5999999
    ranges = no_return(np.asarray(msg.ranges, dtype=np.float64), min_m=float(msg.range_min), max_m=max_m)
    return ScanRecord(t_ns, float(msg.angle_min), float(msg.angle_increment), ranges, max_m)


def odometry_pose(msg: Any, t_ns: int) -> PoseRecord:
    """The pose of a ``nav_msgs/Odometry`` stamped ``t_ns`` (its child frame is the base frame)."""
    p = msg.pose.pose
    return PoseRecord(t_ns, float(p.position.x), float(p.position.y), quaternion_yaw(p.orientation))


def twist_command(msg: Any, t_ns: int) -> CommandRecord:
    """The command of a ``geometry_msgs/Twist`` or ``TwistStamped`` stamped ``t_ns``."""
    tw = getattr(msg, "twist", msg)  # TwistStamped or Twist
    return CommandRecord(t_ns, float(tw.linear.x), float(tw.angular.z))
