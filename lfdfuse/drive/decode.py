"""Messages off the wire into our own small records, and the Twist we send back.

Two dialects (DESIGN §15): what ``foxglove_bridge`` sends — CDR with ``ros2msg`` schemas
(``sensor_msgs/msg/LaserScan``, ``nav_msgs/msg/Odometry``, ``tf2_msgs/msg/TFMessage``,
``geometry_msgs/msg/Twist``), deserialised by ``rosbags`` from the schema text the server
advertises (no ROS install) — and what ``lfdfuse teleop --input foxglove`` sends: JSON
``foxglove.LaserScan``, ``foxglove.PoseInFrame``, ``foxglove.FrameTransform`` and
``lfdfuse.TargetDetections``, read by the log's own codecs. Which function reads which
(encoding, schema) is :mod:`lfdfuse.drive.decoders`' registry. Nothing format-specific leaks out:
every decoder returns a :class:`LiveScan`, :class:`LiveOdom`, :class:`LiveTf`,
:class:`LiveTwist` or :class:`LiveTargets`, or raises :class:`DecodeError`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from functools import lru_cache
from typing import Any

import numpy as np
import orjson
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from lfdfuse.log.messages import decode_detections, decode_pose, decode_scan, yaw_of
from lfdfuse.log.stamps import ROBOT_FRAME, from_stamp
from lfdfuse.robot.readings import Detection
from lfdfuse.robot.records import ScanRecord, no_return
from lfdfuse.robot.ros import (
    frame_name,
    header_ns,
    odometry_pose,
    quaternion_matrix,
    scan_record,
    transform_matrix,
    twist_command,
)
from lfdfuse.sim.sensors import LaserParams
from lfdfuse.sources.teleop.inputs import TwistError, parse_twist

TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
#: lfdfuse's JSON scans carry no max range: they come from the simulated laser
JSON_MAX_RANGE_M = LaserParams().max_range_m


class DecodeError(ValueError):
    """A message that cannot be decoded (the session warns once and goes on)."""


class Role(Enum):
    """What a channel is to ``drive``."""

    SCAN = "scan"  #: the laser
    ODOM = "odom"  #: odometry (only its increments are used)
    TF = "tf"  #: transforms (the laser mounting)
    CMD = "cmd"  #: the robot's own velocity commands (recorded in --shadow)
    TARGETS = "targets"  #: a camera's target detections (lfdfuse's simulated robot)


@dataclass(frozen=True, eq=False)
class LiveScan:
    """A scan in its sensor frame ``frame`` (no return = ``inf``)."""

    frame: str
    record: ScanRecord


@dataclass(frozen=True)
class LiveOdom:
    t_ns: int
    x: float
    y: float
    theta: float
    base_frame: str  # the odometry's child frame ('' when the message does not say)


@dataclass(frozen=True)
class Transform:
    """``parent → child`` as a 4×4 homogeneous matrix (as nested tuples: frozen)."""

    parent: str
    child: str
    matrix: tuple[tuple[float, ...], ...]


@dataclass(frozen=True)
class LiveTf:
    transforms: tuple[Transform, ...]


@dataclass(frozen=True)
class LiveTwist:
    v_mps: float
    omega_rps: float


@dataclass(frozen=True)
class LiveTargets:
    t_ns: int
    detections: tuple[Detection, ...]


Record = LiveScan | LiveOdom | LiveTf | LiveTwist | LiveTargets
Decoder = Callable[[bytes], Record]


def _frozen(m: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in m)


# -- CDR (foxglove_bridge) ----------------------------------------------------------------------


@lru_cache(maxsize=64)  # parsing a definition takes ~0.1 s; a reconnect advertises the same ones
def typestore_for(schema_name: str, schema: str) -> Typestore:
    """A type store holding ``schema_name`` from its ``ros2msg`` text (with its dependencies);
    the standard ROS 2 (Humble) store when the server sent no text."""
    if not schema.strip():
        return get_typestore(Stores.ROS2_HUMBLE)
    store = get_typestore(Stores.EMPTY)
    try:
        store.register(get_types_from_msg(schema, schema_name))
    except Exception as exc:  # rosbags raises several types for a bad definition
        raise DecodeError(f"cannot parse the ros2msg schema of {schema_name} ({exc})") from None
    return store


def _cdr_scan(m: Any) -> LiveScan:
    start, inc, n = float(m.angle_min), float(m.angle_increment), len(m.ranges)
    if n == 0 or not (math.isfinite(start) and math.isfinite(inc) and math.isfinite(float(m.range_max))):
        raise DecodeError(f"a malformed LaserScan ({n} beams, angle_min {start}, increment {inc})")
    if n > 1 and inc == 0.0:
        raise DecodeError(f"a malformed LaserScan ({n} beams all at one bearing)")
    return LiveScan(frame_name(m.header.frame_id), scan_record(m, header_ns(m.header)))


def _cdr_odom(m: Any) -> LiveOdom:
    p = odometry_pose(m, header_ns(m.header))
    return LiveOdom(p.t_ns, p.x, p.y, p.theta, frame_name(m.child_frame_id))


def _cdr_tf(m: Any) -> LiveTf:
    out = []
    for tr in m.transforms:
        mat = transform_matrix(tr.transform)
        out.append(Transform(frame_name(tr.header.frame_id), frame_name(tr.child_frame_id), _frozen(mat)))
    return LiveTf(tuple(out))


def _cdr_twist(m: Any) -> LiveTwist:
    c = twist_command(m, 0)  # a plain Twist has no stamp
    if not (math.isfinite(c.v_mps) and math.isfinite(c.omega_rps)):
        raise DecodeError("a Twist that is not finite")
    return LiveTwist(c.v_mps, c.omega_rps)


# -- JSON (lfdfuse's own server) ----------------------------------------------------------------


def _json_scan(m: dict[str, Any]) -> LiveScan:
    s = decode_scan(m)
    n = len(s.ranges_m)
    if n == 0:
        raise DecodeError("a scan without beams")
    inc = (s.end_rad - s.start_rad) / (n - 1) if n > 1 else 0.0
    ranges = no_return(np.asarray(s.ranges_m, dtype=np.float64), max_m=JSON_MAX_RANGE_M)
    rec = ScanRecord(from_stamp(m["timestamp"]), s.start_rad, inc, ranges, JSON_MAX_RANGE_M)
    return LiveScan(frame_name(str(m.get("frame_id", ROBOT_FRAME))), rec)


def _json_pose(m: dict[str, Any]) -> LiveOdom:
    x, y, th = decode_pose(m)
    return LiveOdom(from_stamp(m["timestamp"]), x, y, th, ROBOT_FRAME)


def _json_tf(m: dict[str, Any]) -> LiveTf:
    t, q = m["translation"], m["rotation"]
    mat = quaternion_matrix(t["x"], t["y"], t.get("z", 0.0), q["x"], q["y"], q["z"], q["w"])
    yaw_of(q)  # validates the quaternion's fields
    parent, child = frame_name(m["parent_frame_id"]), frame_name(m["child_frame_id"])
    return LiveTf((Transform(parent, child, _frozen(mat)),))


def _json_twist(data: bytes) -> Record:
    try:
        v, w = parse_twist(data)
    except TwistError as exc:
        raise DecodeError(f"undecodable Twist ({exc})") from None
    return LiveTwist(v, w)


def _json_targets(m: dict[str, Any]) -> LiveTargets:
    return LiveTargets(from_stamp(m["timestamp"]), decode_detections(m))


# -- the command we send ------------------------------------------------------------------------


@dataclass(frozen=True)
class TwistEncoder:
    """The command we send in one encoding and type: its schema text and ``encode(v, ω, t_ns)``.

    ``t_ns`` (the robot's clock) stamps a ``TwistStamped``; a plain ``Twist`` has no stamp.
    """

    encoding: str  # cdr | json
    schema_name: str  # geometry_msgs/msg/Twist or geometry_msgs/msg/TwistStamped
    schema: str
    encode: Callable[[float, float, int], bytes]


def twist_encoder(supported: tuple[str, ...], *, stamped: bool = False) -> TwistEncoder:
    """CDR when the server takes it (a ROS 2 bridge), else JSON (lfdfuse's own server);
    ``geometry_msgs/msg/TwistStamped`` when ``stamped`` (a robot whose command topic has that
    type: ROS 2 Jazzy's Nav2 and TurtleBot 4), else ``geometry_msgs/msg/Twist``.

    An empty list (an old server that does not say) means CDR: what foxglove_bridge takes.
    """
    name = TWIST_STAMPED if stamped else TWIST
    if "cdr" in supported or not supported:
        store = get_typestore(Stores.ROS2_HUMBLE)
        text, _ = store.generate_msgdef(name)
        T = store.types
        twist, vec = T[TWIST], T["geometry_msgs/msg/Vector3"]

        def cdr(v: float, w: float, t_ns: int) -> bytes:
            msg = twist(vec(v, 0.0, 0.0), vec(0.0, 0.0, w))
            if stamped:
                t_ns = max(t_ns, 0)
                stamp = T["builtin_interfaces/msg/Time"](t_ns // 1_000_000_000, t_ns % 1_000_000_000)
                msg = T[TWIST_STAMPED](T["std_msgs/msg/Header"](stamp, ROBOT_FRAME), msg)
            return bytes(store.serialize_cdr(msg, name))

        return TwistEncoder("cdr", name, text, cdr)
    if "json" in supported:

        def js(v: float, w: float, t_ns: int) -> bytes:
            zero = {"x": 0.0, "y": 0.0, "z": 0.0}
            msg: dict[str, Any] = {"linear": {**zero, "x": v}, "angular": {**zero, "z": w}}
            if stamped:
                t_ns = max(t_ns, 0)
                stamp = {"sec": t_ns // 1_000_000_000, "nanosec": t_ns % 1_000_000_000}
                msg = {"header": {"stamp": stamp, "frame_id": ROBOT_FRAME}, "twist": msg}
            return orjson.dumps(msg)

        return TwistEncoder("json", name, "", js)
    raise DecodeError(
        f"the server takes neither CDR nor JSON from clients (it takes: {', '.join(supported)})"
    )
