"""``lfdfuse record``: a live robot, driven by a person with their own teleop, recorded as a demo.

:func:`record` listens to the robot through either transport of ``drive`` — ROS 2 over DDS
(``ros2://domain/N``) or a Foxglove WebSocket server (``ws://…``) — and publishes nothing: the
scan, the odometry, tf and the commands on ``--cmd`` (whoever sends them: ``teleop_twist_keyboard``,
a joystick, Foxglove's Teleop panel). When it ends (``--duration``, SIGINT/SIGTERM, or
:meth:`~lfdfuse.drive.options.Stopper.stop`) what came is written by ``import``'s own writer
(:func:`~lfdfuse.sources.importers.convert.write_demo`): the same channels and provenance, with
``teacher: human``, so ``segment`` takes it directly. A lost link is retried with back-off while
the run lasts.

A plain ``Twist`` has no stamp: a command is stamped on the robot's clock, the last scan's stamp
plus the wall time since that scan arrived (the order the robot saw scans and commands in). The
laser's mounting is tf's (the chain from the scan's frame to the odometry's child frame, else
``base_link``); the command's publisher is named when DDS reports one (its participant's name).
"""

from __future__ import annotations

import asyncio
import math
import time
from collections import Counter
from collections.abc import Iterator
from contextlib import suppress
from dataclasses import dataclass, field
from pathlib import Path

from lfdfuse.drive.decode import LiveOdom, LiveScan, LiveTf, LiveTwist, Role
from lfdfuse.drive.frames import TfTree
from lfdfuse.drive.links import Links
from lfdfuse.drive.options import DriveError, Notify, Stopper
from lfdfuse.drive.session import TRANSPORTS
from lfdfuse.drive.transport import Arrival, Link, Lost, Ready, Topics, Transport
from lfdfuse.robot.records import CommandRecord, PoseRecord, ScanRecord
from lfdfuse.robot.ros import BASE_FRAMES
from lfdfuse.sources.importers.convert import ImportOptions, ImportSummary, write_demo
from lfdfuse.sources.importers.records import SourceError, SourceInfo, TopicChoice

#: how long after connecting the scan must be found (a later link may wait longer)
READY_TIMEOUT_S = 3.0


@dataclass(frozen=True)
class RecordOptions:
    url: str  # ros2://domain/N or ws://HOST:PORT
    scan_topic: str = "/scan"
    odom_topic: str = "/odom"
    cmd_topic: str = "/cmd_vel"
    duration_s: float | None = None


@dataclass(frozen=True)
class RecordSummary:
    """What was received and what the demo holds (``demo``: ``import``'s own summary)."""

    demo: ImportSummary
    received: dict[str, int]  # messages per role
    connections: int
    ended: str
    warnings: dict[str, int] = field(default_factory=dict)


@dataclass
class LiveSource:
    """What a live link delivered, as an importer's :class:`~lfdfuse.sources.importers.records.Source`."""

    info: SourceInfo
    scans: list[ScanRecord]
    commands: list[CommandRecord]
    poses: list[PoseRecord]
    dropped: Counter[str] = field(default_factory=Counter)

    def iter_scans(self) -> Iterator[ScanRecord]:
        return iter(self.scans)

    def iter_commands(self) -> Iterator[CommandRecord]:
        return iter(self.commands)

    def iter_poses(self) -> Iterator[PoseRecord]:
        return iter(self.poses)


class _Recording:
    def __init__(self, opts: RecordOptions, transport: Transport, notify: Notify, stopper: Stopper) -> None:
        self.opts, self.transport, self.notify, self.stopper = opts, transport, notify, stopper
        self.scans: list[ScanRecord] = []
        self.commands: list[CommandRecord] = []
        self.poses: list[PoseRecord] = []
        self.tf = TfTree()
        self.laser = ""  # the scan's frame
        self.base = ""  # the odometry's child frame
        self.received: Counter[str] = Counter()
        self.warned: Counter[str] = Counter()
        self.publishers: set[str] = set()
        self._clock: tuple[int, float] | None = None  # (last scan stamp, its arrival)
        self.links = Links(transport, stopper, warn=self.warn, notify=notify)

    def warn(self, key: str, text: str) -> None:
        if not self.warned[key]:
            self.notify(f"warning: {text}")
        self.warned[key] += 1

    def arrival(self, ev: Arrival) -> None:
        rec = ev.record
        self.received[ev.role.value] += 1
        if ev.role is Role.SCAN and isinstance(rec, LiveScan):
            if self.scans and rec.record.t_ns <= self.scans[-1].t_ns:
                return  # a stamp that does not advance: a replayed or reordered scan
            self.laser = rec.frame
            self.scans.append(rec.record)
            self._clock = (rec.record.t_ns, ev.arrived_s)
        elif ev.role is Role.ODOM and isinstance(rec, LiveOdom):
            self.poses.append(PoseRecord(rec.t_ns, rec.x, rec.y, rec.theta))
            self.base = self.base or rec.base_frame
        elif ev.role is Role.TF and isinstance(rec, LiveTf):
            self.tf.add(rec)
        elif ev.role is Role.CMD and isinstance(rec, LiveTwist) and self._clock is not None:
            t_ns, at = self._clock
            t = t_ns + round((ev.arrived_s - at) * 1e9)
            if self.commands and t <= self.commands[-1].t_ns:
                t = self.commands[-1].t_ns + 1
            self.commands.append(CommandRecord(t, rec.v_mps, rec.omega_rps))

    async def link(self, link: Link, stop: asyncio.Event) -> None:
        """Serve one link until ``stop`` or :class:`Lost`."""
        ready = False
        ready_by = time.monotonic() + READY_TIMEOUT_S

        async def serve() -> None:
            nonlocal ready
            async for ev in link:
                if isinstance(ev, Ready):
                    ready = True
                    self.notify(
                        f"recording {self.opts.scan_topic}, {self.opts.odom_topic}, tf, {self.opts.cmd_topic}"
                    )
                else:
                    self.arrival(ev)
                    self.publishers.update(link.publishers(self.opts.cmd_topic))

        task = asyncio.create_task(serve())
        stopping = asyncio.create_task(stop.wait())
        try:
            while True:
                timeout = None if ready else max(0.0, ready_by - time.monotonic())
                done, _ = await asyncio.wait(
                    {task, stopping}, timeout=timeout, return_when=asyncio.FIRST_COMPLETED
                )
                if task in done:
                    task.result()
                    raise Lost("the link ended")
                if stopping in done:
                    return
                if not ready:
                    if self.connections == 1:
                        raise DriveError(link.not_ready())
                    ready_by = time.monotonic() + READY_TIMEOUT_S
        finally:
            for t in (task, stopping):
                t.cancel()
                with suppress(asyncio.CancelledError, Exception):
                    await t
            self.publishers.update(link.publishers(self.opts.cmd_topic))
            await link.close()

    @property
    def connections(self) -> int:
        return self.links.connections

    async def run(self) -> str:
        return await self.links.run(self.link, duration_s=self.opts.duration_s)

    def source(self, fmt: str) -> LiveSource:
        bases = tuple(dict.fromkeys(b for b in (self.base, *BASE_FRAMES) if b))
        found = self.tf.mount(self.laser, bases) if self.laser else None
        names = sorted(self.publishers)
        info = SourceInfo(
            format=fmt,
            topics={"scan": self.opts.scan_topic, "cmd": self.opts.cmd_topic, "odom": self.opts.odom_topic},
            mount=found[0] if found else None,
            mount_from=found[1] if found else "",
            teacher="human",
            cmd_publisher=names[0] if len(names) == 1 else None,
        )
        return LiveSource(info, self.scans, self.commands, self.poses)


def transport_of(opts: RecordOptions) -> tuple[Transport, str]:
    """The transport of ``opts.url`` (listening to ``--cmd`` too, publishing nothing), and its format name."""
    scheme, sep, _ = opts.url.partition("://")
    make = TRANSPORTS.get(scheme) if sep else None
    if make is None:
        raise DriveError(f"--connect must be a ws://HOST:PORT URL (or use --ros2), got {opts.url!r}")
    topics = Topics(opts.scan_topic, opts.odom_topic, opts.cmd_topic, shadow=True)
    return make(opts.url, topics), ("ros2-dds" if scheme == "ros2" else "foxglove")


def record(
    opts: RecordOptions,
    *,
    out: str | Path,
    notify: Notify = lambda _: None,
    stopper: Stopper | None = None,
) -> RecordSummary:
    """Record the robot at ``opts.url`` until the duration or a stop, into the demo ``out``."""
    if opts.duration_s is not None and not (opts.duration_s > 0 and math.isfinite(opts.duration_s)):
        raise DriveError("--duration must be a positive number of seconds")
    transport, fmt = transport_of(opts)
    rec = _Recording(opts, transport, notify, stopper or Stopper())
    ended = asyncio.run(rec.run())
    if not rec.scans:
        raise SourceError(f"nothing to write: no scan came on {opts.scan_topic} ({ended})")
    options = ImportOptions(
        topics=TopicChoice(opts.scan_topic, opts.cmd_topic, opts.odom_topic), teacher="human"
    )
    demo = write_demo(rec.source(fmt), source=opts.url, out=out, options=options, command="record")
    return RecordSummary(demo, dict(rec.received), rec.connections, ended, dict(rec.warned))
