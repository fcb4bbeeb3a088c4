"""What every importer yields: our own small records, nothing format-specific.

An importer (one module per source format) opens a log and exposes a :class:`Source`: a
:class:`SourceInfo` (format, topics picked, laser mounting, robot limits) and three generators of
the robot's records (:mod:`lfdfuse.robot.records`) in the source's own time order: scans,
commands and poses. Time stamps are int64 nanoseconds (epoch stamps stay exact); scans are in the
*sensor* frame, with every beam that has no return already set to ``inf``. Messages an importer
skips are counted by reason in ``Source.dropped``.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Protocol

from lfdfuse.errors import LfdError
from lfdfuse.robot.mount import Mount
from lfdfuse.robot.records import CommandRecord, PoseRecord, ScanRecord


class SourceError(LfdError):
    """A robot log cannot be imported (unknown format, unreadable, missing topic)."""


@dataclass(frozen=True)
class Publisher:
    """One node publishing on a topic (a ROS 1 connection's ``callerid``): how many messages, the
    first and last stamp (int64 ns)."""

    name: str
    count: int
    first_ns: int
    last_ns: int


@dataclass(frozen=True)
class SourceInfo:
    """What an importer found in a log, before reading its messages.

    ``topics`` maps a role (``scan``, ``cmd``, ``odom``) to the topic or line type used;
    ``mount`` is None when the log does not say where the laser sits; robot limits are None
    when the log does not state them. ``publishers`` names the nodes publishing the commands when
    the log records several (ROS 1) or one was picked (``cmd_publisher``); empty otherwise.
    """

    format: str
    topics: dict[str, str]
    mount: Mount | None = None
    mount_from: str = ""
    v_max_mps: float | None = None
    omega_max_rps: float | None = None
    teacher: str = "unknown"
    notes: tuple[str, ...] = ()
    publishers: tuple[Publisher, ...] = ()
    cmd_publisher: str | None = None


class Source(Protocol):
    """An opened robot log. The generators may be called more than once, in any order."""

    info: SourceInfo
    dropped: Counter[str]

    def iter_scans(self) -> Iterator[ScanRecord]: ...

    def iter_commands(self) -> Iterator[CommandRecord]: ...

    def iter_poses(self) -> Iterator[PoseRecord]: ...


@dataclass(frozen=True)
class TopicChoice:
    """Topics the user named (None: pick automatically); ``cmd_publisher``: only the commands this
    node published (ROS 1 ``callerid``; None: every publisher's, merged in time order)."""

    scan: str | None = None
    cmd: str | None = None
    odom: str | None = None
    cmd_publisher: str | None = None


def stamp_ns(text: str) -> int:
    """A decimal seconds stamp (``"1134865053.682367"``, ``"1e-3"``) into int nanoseconds, exactly.

    >>> stamp_ns("1134865053.682367"), stamp_ns("0.5"), stamp_ns("12")
    (1134865053682367000, 500000000, 12000000000)
    """
    s = text.strip()
    if "e" in s.lower():  # rare; a float is exact enough for relative stamps written this way
        return round(float(s) * 1e9)
    neg = s.startswith("-")
    whole, _, frac = s.lstrip("+-").partition(".")
    ns = int(whole or "0") * 1_000_000_000 + int((frac + "000000000")[:9])
    return -ns if neg else ns
