"""The live MCAP of ``drive -o live.mcap``: what was received, why the network turned, what was sent.

Per fresh scan (the control tick): ``/scan`` (in the base frame, as ``import`` writes it),
``/pose`` and ``/tf`` (the latest odometry, frame ``odom``), ``/targets`` when the robot has a
camera, the ``/lfd/*`` channels of ``execute`` (written by its own
:class:`~lfdfuse.execute.record.LfdRecorder`), ``/cmd_vel`` (the command sent; in ``--shadow``
the robot's own) and ``/lfd/command`` (``lfdfuse.DriveCommand``: the network's command, sent
or not, its latency and, in shadow, its heading error). Zero Twists of the watchdog and of the
exit are on ``/cmd_vel`` and ``/lfd/command`` too. Log times are the robot's stamps, kept
strictly increasing: a watchdog command between scans is placed by the wall time since the
last scan, and one before the first scan (a new link's zero Twist) by the wall time until it,
once it comes — the log starts on the robot's clock, not at 0.
"""

from __future__ import annotations

import time
from dataclasses import replace

from lfdfuse.drive.core import DriveCore, Tick
from lfdfuse.execute.record import LfdRecorder
from lfdfuse.log import messages as msg
from lfdfuse.log.command import DriveCommand
from lfdfuse.log.writer import LogWriter

ODOM_FRAME = "odom"


class LogClock:
    """Strictly increasing log times from the robot's stamps and, between scans, the wall clock."""

    def __init__(self) -> None:
        self.last_ns = -1
        self._scan: tuple[int, float] | None = None  # (stamp, wall s) of the last scan

    @property
    def anchored(self) -> bool:
        """A scan has set the clock (:meth:`at_wall` before it has nothing to count from)."""
        return self._scan is not None

    def anchor(self, stamp_ns: int, wall_s: float) -> None:
        """Set the clock before a scan does (the first scan's stamp, or our epoch clock)."""
        self._scan = (stamp_ns, wall_s)

    def at_scan(self, stamp_ns: int, wall_s: float) -> int:
        t = max(stamp_ns, self.last_ns + 1, 0)
        self._scan = (t, wall_s)
        self.last_ns = t
        return t

    def at_wall(self, wall_s: float) -> int:
        base = self._scan
        t = base[0] + round((wall_s - base[1]) * 1e9) if base is not None else 0
        t = max(t, self.last_ns + 1, 0)
        self.last_ns = t
        return t


class LiveRecorder:
    """Writes a live run (see the module docstring) into an open :class:`LogWriter`."""

    def __init__(self, log: LogWriter, core: DriveCore, *, shadow: bool) -> None:
        self.log = log
        self.core = core
        self.shadow = shadow
        self.clock = LogClock()
        self._lfd: LfdRecorder | None = None
        self._early: list[tuple[float, str]] = []  # zero Twists before the first scan: (wall s, source)
        log.add_topic(DriveCommand.TOPIC, DriveCommand.SCHEMA)
        self.ticks = 0

    def tick(self, tick: Tick, *, wall_s: float, latency_ms: float | None) -> None:
        core, log = self.core, self.log
        assert core.frame is not None and core.driver is not None and core.mount is not None
        if not self.clock.anchored:
            self._place_early(tick.obs.t_ns, wall_s)
        t = self.clock.at_scan(tick.obs.t_ns, wall_s)
        obs = tick.obs
        scan = msg.laser_scan(t, obs.reading.ranges_m, core.frame.geometry)
        mount = core.mount
        scan["pose"] = {
            "position": {"x": mount.x_m, "y": mount.y_m, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
        }
        log.write("/scan", t, scan)
        if core.odom is not None:
            p = obs.pose
            pose = msg.pose_in_frame(t, p.x, p.y, p.theta)
            pose["frame_id"] = ODOM_FRAME
            tf = msg.frame_transform(t, p.x, p.y, p.theta)
            tf["parent_frame_id"] = ODOM_FRAME
            log.write("/tf", t, tf)
            log.write("/pose", t, pose)
        if core.inputs.camera:
            log.write("/targets", t, msg.target_detections(t, obs.reading.detections))
        if self._lfd is None:
            self._lfd = LfdRecorder(log, core.driver)
        self._lfd.record(replace(obs, t_ns=t), tick.network)
        held = tick.robot if self.shadow else tick.network
        if held is not None:
            log.write("/cmd_vel", t, msg.twist(t, held[0], held[1]))
        v, w = tick.network
        cmd = DriveCommand(t, v, w, "network", not self.shadow, latency_ms, tick.heading_error_deg)
        log.write_raw(DriveCommand.TOPIC, t, cmd.encode())
        self.ticks += 1

    def zero(self, *, wall_s: float, source: str) -> None:
        """A zero Twist sent by the watchdog (``stale``) or on exit (``stop``)."""
        if not self.clock.anchored:
            self._early.append((wall_s, source))  # placed when the first scan sets the clock
            return
        self._write_zero(self.clock.at_wall(wall_s), source)

    def _place_early(self, stamp_ns: int, wall_s: float) -> None:
        """The zero Twists before the clock was set, back from ``stamp_ns`` at ``wall_s``."""
        self.clock.anchor(stamp_ns, wall_s)
        early, self._early = self._early, []
        for at, source in early:
            self._write_zero(self.clock.at_wall(at), source)

    def _write_zero(self, t: int, source: str) -> None:
        self.log.write("/cmd_vel", t, msg.twist(t, 0.0, 0.0))
        self.log.write_raw(DriveCommand.TOPIC, t, DriveCommand(t, 0.0, 0.0, source, True).encode())

    def close(self) -> None:
        """A run without a scan: place its zero Twists on our epoch clock."""
        if not self.clock.anchored:
            self._place_early(time.time_ns(), time.monotonic())
