"""ROS bags (ROS 1 ``.bag``; ROS 2 MCAP, rosbag2 folders and ``.db3``) through ``rosbags``.

No ROS installation is needed: ``rosbags`` reads both bag generations and deserialises with the
definitions embedded in the bag, or with a standard type store when a bag has none. Topics are
picked by message type (``/scan``, ``/cmd_vel`` and ``/odom`` preferred when several fit); the
laser mounting comes from ``/tf_static`` (or ``/tf``): the chain from the scan's frame up to the
robot's base frame. Every stamp is the bag's record time, so scans, commands and poses share one
clock.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.rosbag1 import Reader as Reader1
from rosbags.rosbag1 import ReaderError as Reader1Error
from rosbags.rosbag2 import Reader as Reader2
from rosbags.rosbag2 import ReaderError as Reader2Error
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, TypesysError, get_typestore
from rosbags.typesys.store import Typestore

from lfdfuse.robot.mount import Mount, MountError
from lfdfuse.robot.records import CommandRecord, PoseRecord, ScanRecord
from lfdfuse.robot.ros import (
    BASE_FRAMES,
    frame_name,
    laser_mount,
    odometry_pose,
    on_the_robot,
    scan_record,
    transform_matrix,
    twist_command,
)
from lfdfuse.sources.importers.records import Publisher, SourceError, SourceInfo, TopicChoice

SCAN_TYPES = ("sensor_msgs/msg/LaserScan",)
CMD_TYPES = ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped")
ODOM_TYPES = ("nav_msgs/msg/Odometry",)
TF_TOPICS = ("/tf_static", "/tf")
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


class BagReader(AnyReader):
    """``rosbags``' reader, told which bag generation ``path`` is instead of guessing it from the
    name: ``AnyReader`` takes anything named ``*.bag`` for ROS 1, so a rosbag2 folder named
    ``test_drive.bag`` (a common layout) failed with "Is a directory", and a ROS 1 bag not named
    ``*.bag`` was read as ROS 2. The format's ``detect`` decides by content; this reads it so."""

    def __init__(self, path: Path, *, ros2: bool, default_typestore: Typestore | None = None) -> None:
        if not path.exists():
            raise FileNotFoundError(f"no such file or folder: {path}")
        self.paths = [path]
        self.is2 = ros2
        self.stack = None
        self.connections = []
        self.default_typestore = default_typestore
        self.typestore = get_typestore(Stores.EMPTY)
        try:
            self.readers = [Reader2(path)] if ros2 else [Reader1(path)]
        except (Reader1Error, Reader2Error) as err:
            raise AnyReaderError(*err.args) from None


def callerid(conn: Any) -> str | None:
    """The node that published on a ROS 1 connection (its header's ``callerid``); rosbag2 records
    none."""
    name = getattr(conn.ext, "callerid", None)
    return str(name) if name else None


class BagSource:
    """A ROS 1 or ROS 2 bag opened for import (see the module docstring)."""

    def __init__(self, path: Path, *, fmt: str, topics: TopicChoice, ros2: bool) -> None:
        self.path = path
        self.dropped: Counter[str] = Counter()
        self._ros2 = ros2
        self._store = get_typestore(Stores.ROS2_HUMBLE if ros2 else Stores.ROS1_NOETIC)
        self._cmd_publisher = topics.cmd_publisher
        with self._open() as r:
            conns = r.connections
            scan = _pick(conns, SCAN_TYPES, topics.scan, "/scan", "laser scans", required=True)
            cmd = _pick(conns, CMD_TYPES, topics.cmd, "/cmd_vel", "velocity commands")
            odom = _pick(conns, ODOM_TYPES, topics.odom, "/odom", "odometry")
            assert scan is not None
            self._topics = {"scan": scan, "cmd": cmd, "odom": odom}
            publishers = self._publishers(r, cmd)
            scan_frame = self._first(r, scan, lambda m: frame_name(m.header.frame_id)) or ""
            base = self._first(r, odom, lambda m: frame_name(m.child_frame_id)) if odom else None
            mount, used = self._mount(r, scan_frame, base)
        notes = [f"laser frame {scan_frame!r}" + (f", base frame {base!r}" if base else "")]
        self.info = SourceInfo(
            format=fmt,
            topics={k: v for k, v in self._topics.items() if v},
            mount=mount,
            mount_from=used,
            notes=tuple(notes),
            publishers=publishers,
            cmd_publisher=self._cmd_publisher,
        )

    @contextmanager
    def _open(self) -> Iterator[AnyReader]:
        try:
            with BagReader(self.path, ros2=self._ros2, default_typestore=self._store) as reader:
                yield reader
        except _READ_ERRORS as exc:
            raise SourceError(f"{self.path}: cannot read the bag ({one_line(exc)})") from exc

    def _publishers(self, r: AnyReader, cmd: str | None) -> tuple[Publisher, ...]:
        """The nodes that published on the command topic (ROS 1 only), when there are several or
        one was asked for; checks ``--cmd-publisher``."""
        conns = [c for c in r.connections if c.topic == cmd]
        names = {n for n in map(callerid, conns) if n is not None}
        wanted = self._cmd_publisher
        if wanted is not None:
            if cmd is None:
                raise SourceError("--cmd-publisher: the bag has no velocity command topic")
            if not names:
                raise SourceError(
                    f"--cmd-publisher: the bag does not record who published on {cmd} "
                    "(rosbag2 stores no publisher)"
                )
            if wanted not in names:
                raise SourceError(f"no publisher {wanted} on {cmd} (publishers: {', '.join(sorted(names))})")
        if len(names) < 2 and wanted is None:
            return ()
        stamps: dict[str, list[int]] = {n: [] for n in names}
        for conn, t_ns, _raw in r.messages(connections=conns):
            name = callerid(conn)
            if name is not None:
                stamps[name].append(int(t_ns))
        return tuple(Publisher(name, len(ts), min(ts), max(ts)) for name, ts in sorted(stamps.items()) if ts)

    def _messages(self, r: AnyReader, topic: str | None) -> Iterator[tuple[int, Any]]:
        conns = [c for c in r.connections if c.topic == topic]
        if topic is not None and topic == self._topics.get("cmd") and self._cmd_publisher is not None:
            conns = [c for c in conns if callerid(c) == self._cmd_publisher]
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
        bases = (base,) if base else BASE_FRAMES
        edges: dict[str, tuple[str, np.ndarray]] = {}  # child → (parent, transform): the first one seen
        topic_of: dict[str, str] = {}
        for topic in TF_TOPICS if laser not in bases else ():  # scans in the base frame need no tf
            for _, msg in self._messages(r, topic):
                for tr in msg.transforms:
                    child, parent = frame_name(tr.child_frame_id), frame_name(tr.header.frame_id)
                    if child not in edges and on_the_robot(parent, child):
                        edges[child], topic_of[child] = (parent, transform_matrix(tr.transform)), topic
        try:
            found = laser_mount(edges, laser, bases)
        except MountError as exc:
            raise SourceError(str(exc)) from exc
        if found is None:
            return None, ""
        return found.mount, found.describe(" + ".join(sorted({topic_of[f] for f in found.frames})))

    def iter_scans(self) -> Iterator[ScanRecord]:
        with self._open() as r:
            for t_ns, m in self._messages(r, self._topics["scan"]):
                yield scan_record(m, t_ns)

    def iter_commands(self) -> Iterator[CommandRecord]:
        with self._open() as r:
            for t_ns, m in self._messages(r, self._topics["cmd"]):
                yield twist_command(m, t_ns)

    def iter_poses(self) -> Iterator[PoseRecord]:
        with self._open() as r:
            for t_ns, m in self._messages(r, self._topics["odom"]):
                yield odometry_pose(m, t_ns)


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
        with BagReader(path, ros2=ros2, default_typestore=store) as r:
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
