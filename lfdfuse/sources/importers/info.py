"""What a robot log holds, and what ``lfdfuse import`` would make of it (``lfdfuse inspect``).

A ROS bag (ROS 1 ``.bag``; ROS 2 rosbag2 folder, ``.db3`` or MCAP) is summarised like
``ros2 bag info``: storage, size, time span, and per topic its type, message count and
serialisation, read from the bag's index (no message is decoded for the listing). A CARMEN or
BreezySLAM log is parsed by its importer and its records counted. Either way the summary ends
with the import's own choice, made by the same code ``import`` runs
(:func:`~lfdfuse.sources.importers.open_source`): which topics become ``/scan``, ``/cmd_vel``
and ``/pose``, where the commands come from, where the laser sits — or why import would refuse.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from lfdfuse.robot.mount import Mount
from lfdfuse.sources.importers import detect_format, open_source, ros1, ros2
from lfdfuse.sources.importers.records import SourceError
from lfdfuse.sources.importers.rosbag import BagTopic, bag_listing

#: what each role of the import becomes in the demo
ROLE_TOPICS = {"scan": "/scan", "cmd": "/cmd_vel", "odom": "/pose"}


@dataclass(frozen=True)
class ImportPlan:
    """What ``lfdfuse import`` would read from a log (``problem``: why it would refuse, else None)."""

    topics: dict[str, str]  # role (scan, cmd, odom) → the source's topic or record kind
    commands_from: str  # "recorded on /cmd_vel", "derived from odometry on /odom", "none: …"
    mount: Mount | None
    mount_from: str
    problem: str | None = None
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class LogSummary:
    """A robot log at a glance: storage, time span (int64 ns; None when empty), topics, the import."""

    path: str
    format: str  # an importer's name (ros1, ros2, carmen, breezyslam)
    storage: str
    files: tuple[str, ...]
    size_bytes: int
    start_ns: int | None
    end_ns: int | None
    messages: int
    topics: tuple[BagTopic, ...]
    plan: ImportPlan

    @property
    def duration_s(self) -> float:
        return 0.0 if self.start_ns is None or self.end_ns is None else (self.end_ns - self.start_ns) / 1e9


def _plan(path: Path, fmt: str, counts: dict[str, int]) -> ImportPlan:
    """The import's choice, by the import's own code; a log it would refuse gives the reason."""
    try:
        src = open_source(path, fmt=fmt)
    except SourceError as exc:
        why = str(exc).removeprefix(f"{path}: ")
        return ImportPlan({}, "none", None, "", problem=why)
    info = src.info
    cmd, odom = info.topics.get("cmd"), info.topics.get("odom")
    if cmd is not None and counts.get(cmd, 1) > 0:
        commands_from = f"recorded on {cmd}"
    elif odom is not None:
        commands_from = f"derived from odometry on {odom}"
    else:
        commands_from = "none: no commands and no odometry, so the demo cannot be segmented"
    notes = info.notes
    if len(info.publishers) > 1:
        who = ", ".join(f"{p.name} ({p.count})" for p in info.publishers)
        notes += (
            f"{len(info.publishers)} publishers on {cmd}: {who}; import merges them (--cmd-publisher NAME keeps one)",
        )
    return ImportPlan(dict(info.topics), commands_from, info.mount, info.mount_from, notes=notes)


def summarise(path: Path, *, fmt: str | None = None) -> LogSummary:
    """The summary of the robot log at ``path`` (format detected unless given), or a one-line
    :class:`SourceError` (unknown format, unreadable)."""
    name = fmt or detect_format(path)
    if name in ("ros1", "ros2"):
        where = ros2.bag_path(path) if name == "ros2" else ros1.bag_path(path)
        listing = bag_listing(where, ros2=name == "ros2")
        if name == "ros2" and where.is_file() and where.suffix == ".mcap":
            storage = "MCAP (ROS 2 messages)"
        else:
            storage = listing.storage
        plan = _plan(path, name, {t.topic: t.count for t in listing.topics})
        return LogSummary(
            str(path),
            name,
            storage,
            listing.files,
            listing.size_bytes,
            listing.start_ns,
            listing.end_ns,
            listing.messages,
            listing.topics,
            plan,
        )
    # a text log: its importer parses it; count what it yields
    src = open_source(path, fmt=name)
    scans = [s.t_ns for s in src.iter_scans()]
    commands = sum(1 for _ in src.iter_commands())
    poses = sum(1 for _ in src.iter_poses())
    rows = [
        ("scan", "laser scan", len(scans)),
        ("cmd", "velocity command", commands),
        ("odom", "pose", poses),
    ]
    topics = tuple(
        BagTopic(src.info.topics[role], kind, n, "text") for role, kind, n in rows if role in src.info.topics
    )
    plan = _plan(path, name, {t.topic: t.count for t in topics})
    with path.open("rb") as f:
        gz = f.read(2) == b"\x1f\x8b"
    storage = {"carmen": "CARMEN log", "breezyslam": "BreezySLAM .dat"}.get(name, name) + (
        " (gzip)" if gz else ""
    )
    return LogSummary(
        str(path),
        name,
        storage,
        (path.name,),
        path.stat().st_size,
        min(scans) if scans else None,
        max(scans) if scans else None,
        len(scans) + commands + poses,
        topics,
        plan,
    )
