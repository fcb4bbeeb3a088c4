"""ROS bags (ROS 1 ``.bag``; ROS 2 MCAP, rosbag2 folders and ``.db3``) through ``rosbags``.

No ROS installation is needed: ``rosbags`` reads both bag generations and deserialises with the
definitions embedded in the bag, or with a standard type store when a bag has none. Topics are
picked by message type (``/scan``, ``/cmd_vel`` and ``/odom`` preferred when several fit); the
laser mounting comes from ``/tf_static`` (or ``/tf``): the chain from the scan's frame up to the
robot's base frame. Every stamp is the bag's record time, so scans, commands and poses share one
clock.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.rosbag1 import ReaderError as Reader1Error
from rosbags.rosbag2 import ReaderError as Reader2Error
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, TypesysError, get_typestore

from lfdfuse.sources.importers.records import (
    CommandRecord,
    Mount,
    PoseRecord,
    ScanRecord,
    SourceError,
    SourceInfo,
    TopicChoice,
    no_return,
)

SCAN_TYPES = ("sensor_msgs/msg/LaserScan",)
CMD_TYPES = ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped")
ODOM_TYPES = ("nav_msgs/msg/Odometry",)
TF_TOPICS = ("/tf_static", "/tf")
_BASE_FRAMES = ("base_link", "base_footprint")
_WORLD_FRAMES = ("odom", "map", "world", "earth")
_READ_ERRORS = (
    AnyReaderError,
    Reader1Error,
    Reader2Error,
    SerdeError,
    TypesysError,  # a bag's embedded message definitions that do not parse
    OSError,
    KeyError,
    ValueError,
)


def one_line(exc: BaseException, width: int = 200) -> str:
    """An exception's message on one line (a YAML parser's spans several), at most ``width`` long."""
    text = " ".join(str(exc).split())
    return text if len(text) <= width else text[: width - 1] + "…"


def _frame(name: str) -> str:
    return name.lstrip("/")  # ROS 1 frames may carry a leading slash


def _yaw(q: Any) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def _matrix(tr: Any) -> np.ndarray:
    """A ``geometry_msgs/Transform`` as a 4×4 homogeneous matrix."""
    q, t = tr.rotation, tr.translation
    w, x, y, z = q.w, q.x, q.y, q.z
    m = np.eye(4)
    m[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    m[:3, 3] = [t.x, t.y, t.z]
    return m


def mount_of(m: np.ndarray) -> Mount:
    """The planar mounting of a base→laser transform; a scanner tilted out of the plane is an error."""
    flipped = m[2, 2] < 0.0
    if abs(m[2, 2]) < 0.95:
        raise SourceError("the laser is tilted out of the plane (its z axis is not vertical)")
    return Mount(float(m[0, 3]), float(m[1, 3]), math.atan2(m[1, 0], m[0, 0]), bool(flipped))


class BagSource:
    """A ROS 1 or ROS 2 bag opened for import (see the module docstring)."""

    def __init__(self, path: Path, *, fmt: str, topics: TopicChoice, ros2: bool) -> None:
        self.path = path
        self.dropped: Counter[str] = Counter()
        self._store = get_typestore(Stores.ROS2_HUMBLE if ros2 else Stores.ROS1_NOETIC)
        with self._open() as r:
            conns = r.connections
            scan = _pick(conns, SCAN_TYPES, topics.scan, "/scan", "laser scans", required=True)
            cmd = _pick(conns, CMD_TYPES, topics.cmd, "/cmd_vel", "velocity commands")
            odom = _pick(conns, ODOM_TYPES, topics.odom, "/odom", "odometry")
            assert scan is not None
            self._topics = {"scan": scan, "cmd": cmd, "odom": odom}
            scan_frame = self._first(r, scan, lambda m: _frame(m.header.frame_id)) or ""
            base = self._first(r, odom, lambda m: _frame(m.child_frame_id)) if odom else None
            mount, used = self._mount(r, scan_frame, base)
        notes = [f"laser frame {scan_frame!r}" + (f", base frame {base!r}" if base else "")]
        self.info = SourceInfo(
            format=fmt,
            topics={k: v for k, v in self._topics.items() if v},
            mount=mount,
            mount_from=used,
            notes=tuple(notes),
        )

    @contextmanager
    def _open(self) -> Iterator[AnyReader]:
        try:
            with AnyReader([self.path], default_typestore=self._store) as reader:
                yield reader
        except _READ_ERRORS as exc:
            raise SourceError(f"{self.path}: cannot read the bag ({one_line(exc)})") from exc

    def _messages(self, r: AnyReader, topic: str | None) -> Iterator[tuple[int, Any]]:
        conns = [c for c in r.connections if c.topic == topic]
        if not conns:  # rosbags reads *every* message when given no connection
            return
        for conn, t_ns, raw in r.messages(connections=conns):
            try:
                msg = r.deserialize(raw, conn.msgtype)
            except _READ_ERRORS:
                self.dropped[f"{topic}: undecodable message"] += 1
                continue
            yield int(t_ns), msg

    def _first(self, r: AnyReader, topic: str | None, get: Any) -> str | None:
        for _, msg in self._messages(r, topic):
            return str(get(msg))
        return None

    def _mount(self, r: AnyReader, laser: str, base: str | None) -> tuple[Mount | None, str]:
        bases = (base,) if base else _BASE_FRAMES
        if laser in bases:
            return Mount(), f"the scans are in the base frame {laser!r}"
        edges: dict[str, tuple[str, np.ndarray, str]] = {}  # child → (parent, transform, topic)
        for topic in TF_TOPICS:
            for _, msg in self._messages(r, topic):
                for tr in msg.transforms:
                    child, parent = _frame(tr.child_frame_id), _frame(tr.header.frame_id)
                    if child not in edges and child not in bases and parent not in _WORLD_FRAMES:
                        edges[child] = (parent, _matrix(tr.transform), topic)
        frame, m, used = laser, np.eye(4), []
        while frame not in bases and frame in edges:
            parent, tf, topic = edges[frame]
            m, frame = tf @ m, parent
            used.append(topic)
        if frame not in bases:
            return None, ""
        return mount_of(m), f"{' + '.join(sorted(set(used)))} ({frame} → {laser})"

    def iter_scans(self) -> Iterator[ScanRecord]:
        with self._open() as r:
            for t_ns, m in self._messages(r, self._topics["scan"]):
                max_m = round(float(m.range_max), 6)  # float32 in the message: 5.6 not 5.5999999
                ranges = no_return(np.asarray(m.ranges, dtype=np.float64), min_m=m.range_min, max_m=max_m)
                yield ScanRecord(t_ns, float(m.angle_min), float(m.angle_increment), ranges, max_m)

    def iter_commands(self) -> Iterator[CommandRecord]:
        with self._open() as r:
            for t_ns, m in self._messages(r, self._topics["cmd"]):
                tw = getattr(m, "twist", m)  # TwistStamped or Twist
                yield CommandRecord(t_ns, float(tw.linear.x), float(tw.angular.z))

    def iter_poses(self) -> Iterator[PoseRecord]:
        with self._open() as r:
            for t_ns, m in self._messages(r, self._topics["odom"]):
                p = m.pose.pose
                yield PoseRecord(t_ns, float(p.position.x), float(p.position.y), _yaw(p.orientation))


def _pick(
    conns: list[Any],
    types: tuple[str, ...],
    wanted: str | None,
    preferred: str,
    what: str,
    *,
    required: bool = False,
) -> str | None:
    """The topic for one role: the user's, else ``preferred``, else the busiest of the right type."""
    counts: Counter[str] = Counter()
    all_topics = {c.topic for c in conns}
    for c in conns:
        if c.msgtype in types:
            counts[c.topic] += c.msgcount
    names = ", ".join(sorted(counts)) or "none"
    kinds = " or ".join(t.replace("/msg/", "/") for t in types)
    if wanted is not None:
        if wanted not in all_topics:
            raise SourceError(f"the bag has no topic {wanted} ({what}: {names})")
        if wanted not in counts:
            raise SourceError(f"topic {wanted} is not {kinds} ({what}: {names})")
        return wanted
    if not counts:
        if required:
            raise SourceError(f"the bag has no {kinds} topic ({what})")
        return None
    if preferred in counts:
        return preferred
    ending = [t for t in counts if t.endswith(preferred)]
    pool = ending or list(counts)
    return min(pool, key=lambda t: (-counts[t], t))


@dataclass(frozen=True)
class BagTopic:
    """One topic of a bag: its message type (``pkg/msg/Name``), how many messages, how serialised."""

    topic: str
    msgtype: str
    count: int
    serialization: str  # cdr (ROS 2), ros1


@dataclass(frozen=True)
class BagListing:
    """What ``ros2 bag info`` / ``rosbag info`` say of a bag: storage, time span, topics.

    ``start_ns``/``end_ns`` are the first and last record stamps (int64 ns, epoch), None when the
    bag holds no message; ``topics`` in the order of the topic names.
    """

    storage: str  # "ROS 1 bag v2.0", "rosbag2 sqlite3", "rosbag2 mcap"
    files: tuple[str, ...]  # the storage files, by name
    size_bytes: int
    start_ns: int | None
    end_ns: int | None
    messages: int
    topics: tuple[BagTopic, ...]


def bag_listing(path: Path, *, ros2: bool) -> BagListing:
    """The topics, types, counts and time span of a ROS 1 or ROS 2 bag (read from its index and
    metadata, not its messages), or a one-line :class:`SourceError`."""
    store = get_typestore(Stores.ROS2_HUMBLE if ros2 else Stores.ROS1_NOETIC)
    files = sorted([*path.glob("*.db3"), *path.glob("*.mcap")]) if path.is_dir() else [path]
    if ros2:
        kinds = sorted({"sqlite3" if f.suffix == ".db3" else "mcap" for f in files}) or ["unknown storage"]
        storage = f"rosbag2 {'+'.join(kinds)}"
    else:
        storage = "ROS 1 bag v2.0"
    try:
        with AnyReader([path], default_typestore=store) as r:
            count = int(r.message_count)
            start = int(r.start_time) if count else None
            end = int(r.end_time) - 1 if count else None  # rosbags' end time is one past the last message
            topics = []
            for name, info in sorted(r.topics.items()):
                ser = {
                    getattr(c.ext, "serialization_format", "ros1") for c in info.connections
                }  # ROS 1 connections have none
                topics.append(
                    BagTopic(name, info.msgtype or "(mixed types)", int(info.msgcount), "/".join(sorted(ser)))
                )
    except _READ_ERRORS as exc:
        raise SourceError(f"{path}: cannot read the bag ({one_line(exc)})") from exc
    size = sum(f.stat().st_size for f in files if f.is_file())
    return BagListing(storage, tuple(f.name for f in files), size, start, end, count, tuple(topics))


def is_rosbag1(path: Path) -> bool:
    if not path.is_file():
        return False
    with path.open("rb") as f:
        return f.read(13) == b"#ROSBAG V2.0\n"
