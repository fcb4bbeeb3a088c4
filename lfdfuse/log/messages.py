"""The topic → schema table (DESIGN §5), provenance, raw messages, and every message codec.

Each message family has its own module with encoder and decoder side by side:
:mod:`~lfdfuse.log.sensing` (robot channels), :mod:`~lfdfuse.log.scene` (viewer scenes),
:mod:`~lfdfuse.log.lfd` (the ``/lfd/*`` channels of segment and execute). This module
re-exports them so ``from lfdfuse.log import messages as msg`` reaches every codec.
"""

from __future__ import annotations

from dataclasses import dataclass

from lfdfuse.log.scene import Arrow, arrow_scene, arrow_scene_of, encode_arrow_scene, world_scene
from lfdfuse.log.sensing import (
    decode_detections,
    decode_pose,
    decode_scan,
    decode_twist,
    frame_transform,
    laser_scan,
    pose_in_frame,
    target_detections,
    twist,
)
from lfdfuse.log.stamps import MAP_FRAME, ROBOT_FRAME, from_stamp, quat_z, stamp, yaw_of

#: name of the MCAP metadata record that holds provenance
PROVENANCE = "lfdfuse"


@dataclass(frozen=True)
class RawMessage:
    """A message with its channel and schema exactly as stored (for copying through)."""

    topic: str
    schema_name: str
    schema_encoding: str
    schema_data: bytes
    message_encoding: str
    log_time_ns: int
    publish_time_ns: int
    data: bytes


#: topic → schema name (a contract)
TOPICS: dict[str, str] = {
    "/scan": "foxglove.LaserScan",
    "/sonar": "foxglove.LaserScan",
    "/pose": "foxglove.PoseInFrame",
    "/tf": "foxglove.FrameTransform",
    "/cmd_vel": "lfdfuse.Twist",
    "/targets": "lfdfuse.TargetDetections",
    "/world": "foxglove.SceneUpdate",
}

__all__ = [
    "MAP_FRAME",
    "PROVENANCE",
    "ROBOT_FRAME",
    "TOPICS",
    "Arrow",
    "RawMessage",
    "arrow_scene",
    "arrow_scene_of",
    "encode_arrow_scene",
    "decode_detections",
    "decode_pose",
    "decode_scan",
    "decode_twist",
    "frame_transform",
    "from_stamp",
    "laser_scan",
    "pose_in_frame",
    "quat_z",
    "stamp",
    "target_detections",
    "twist",
    "world_scene",
    "yaw_of",
]
