"""What a live session is asked and what it answers: :class:`DriveOptions` in,
:class:`DriveSummary` out, :class:`Stopper` to end it from outside, :class:`DriveError` when it
cannot start or go on. The run itself is :mod:`lfdfuse.drive.lifecycle`.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass, field

from lfdfuse.drive.core import Applicability
from lfdfuse.drive.safety import Limits
from lfdfuse.errors import LfdError
from lfdfuse.network.table import FusionTable

#: where a session's one-line notes go (the library never prints)
Notify = Callable[[str], None]


class DriveError(LfdError):
    """A live run cannot start or go on (no server, no scan channel, a table it cannot run)."""


@dataclass(frozen=True)
class DriveOptions:
    table: FusionTable
    url: str
    table_name: str = "fusion.yaml"
    scan_topic: str = "/scan"
    odom_topic: str = "/odom"
    cmd_topic: str = "/cmd_vel"
    shadow: bool = False
    max_speed: float | None = None
    max_turn: float | None = None
    duration_s: float | None = None
    command: str = "drive"


@dataclass(frozen=True)
class DriveSummary:
    ticks: int  # fresh scans the network decided on
    sent: int  # commands published (network + zero Twists)
    zeros: int  # zero Twists of the watchdog and the exit
    connections: int
    duration_s: float
    latency_ms: tuple[float, float] | None  # p50, p99 (scan arrival → command sent/computed)
    latencies_ms: tuple[float, ...]  # every tick's, in order
    cpu_ms: tuple[float, ...]  # the CPU time this thread spent over each tick's latency
    agreement_deg: float | None  # --shadow: mean §12 heading error against the robot's commands
    agreement_ticks: int
    odometry_m: float  # path length by odometry
    ended: str
    encoding: str  # of our Twist ('' in --shadow)
    limits: Limits
    limits_from: str
    mount_from: str
    behaviors: Applicability | None
    warnings: dict[str, int] = field(default_factory=dict)
    out: str = ""


class Stopper:
    """Ends a session from a signal handler, a timer or a test (thread-safe via the loop)."""

    def __init__(self) -> None:
        self.reason = ""
        self._event: asyncio.Event | None = None
        self._loop: asyncio.AbstractEventLoop | None = None

    def bind(self, loop: asyncio.AbstractEventLoop, event: asyncio.Event) -> None:
        self._loop, self._event = loop, event

    def stop(self, reason: str) -> None:
        if not self.reason:
            self.reason = reason
        if self._loop is not None and self._event is not None:
            self._loop.call_soon_threadsafe(self._event.set)
