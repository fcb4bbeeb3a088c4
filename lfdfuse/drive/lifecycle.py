"""The run of ``lfdfuse drive``, whatever the transport: signals, duration, reconnecting, stopping safely.

:func:`run_live` runs one live session against a robot reached through a
:class:`~lfdfuse.drive.transport.Transport` until ``--duration``, a signal (SIGINT/SIGTERM) or
:meth:`Stopper.stop`. Nothing here knows a protocol. Once a link is ready
the :class:`~lfdfuse.drive.core.DriveCore` starts (with the inputs the robot has), and each
scan that arrives is handed to it and its command sent at once, in the same task — the
scan → command latency is decoding plus one network tick. A watchdog task sends a zero Twist
every period while no fresh scan came for 0.5 s. Every exit path with an open link sends a zero
Twist first; a lost link is retried with back-off while the duration lasts, and nothing is sent
while it is down. A run that never connected is an error. The library never prints: ``notify``
gets one-line notes.
"""

from __future__ import annotations

import asyncio
import gc
import math
import time
from collections import Counter
from contextlib import nullcontext, suppress
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse import __version__
from lfdfuse.drive.core import Applicability, DriveCore, Inputs, Skip, applicability, check_applicable
from lfdfuse.drive.decode import LiveOdom, LiveScan, LiveTargets, LiveTf, LiveTwist, Role
from lfdfuse.drive.links import Links
from lfdfuse.drive.options import DriveError, DriveOptions, DriveSummary, Notify, Stopper
from lfdfuse.drive.record import LiveRecorder
from lfdfuse.drive.safety import WATCHDOG_PERIOD_S, limits_of
from lfdfuse.drive.transport import Arrival, Link, Lost, Ready, Transport
from lfdfuse.log.writer import LogWriter

#: how long after connecting the link must be ready (the scan found)
READY_TIMEOUT_S = 3.0
STATUS_PERIOD_S = 5.0
ZERO_PERIOD_S = 0.1  # the zero Twist's repeat while blind


def _p(values: list[float], q: float) -> float:
    return float(np.percentile(np.asarray(values), q))


class _Session:
    def __init__(
        self,
        opts: DriveOptions,
        *,
        transport: Transport,
        notify: Notify,
        log: LogWriter | None,
        stopper: Stopper,
    ) -> None:
        self.opts = opts
        self.transport = transport
        self.notify = notify
        self.log = log
        self.stopper = stopper
        self.limits, self.limits_from = limits_of(
            opts.table.estimated_by, max_speed=opts.max_speed, max_turn=opts.max_turn
        )
        self.core: DriveCore | None = None
        self.recorder: LiveRecorder | None = None
        self.app: Applicability | None = None
        self.latencies: list[float] = []
        self.cpu: list[float] = []
        self.sent = self.zeros = 0
        self.warned: Counter[str] = Counter()
        self.command = ""  # the command's encoding and type, as the last ready link said
        self.ready = False  # the current link is ready (commands may go out)
        self._busy = False  # an event of the link is being handled
        self._ending = False  # the link is being closed: serve no further event
        self.odometry_m = 0.0
        self._last_odom: LiveOdom | None = None
        self._blind_noted = False
        self._last_status = 0.0
        self._last_zero_s = -math.inf
        self._robot_clock: tuple[int, float] | None = None  # (stamp, monotonic s) of the last tick
        self.links = Links(transport, stopper, warn=self.warn, notify=notify, reconnected=self._reconnected)

    def _robot_now_ns(self) -> int:
        """The robot's clock now, from the last scan's stamp (our epoch clock before any)."""
        if self._robot_clock is None:
            return time.time_ns()
        t_ns, at = self._robot_clock
        return t_ns + int((time.monotonic() - at) * 1e9)

    # -- notes ------------------------------------------------------------------------------
    def warn(self, key: str, text: str) -> None:
        if not self.warned[key]:
            self.notify(f"warning: {text}")
        self.warned[key] += 1

    # -- one link ---------------------------------------------------------------------------
    async def connection(self, link: Link, stop: asyncio.Event) -> None:
        """Serve one open link until ``stop`` or the link drops (:class:`Lost`)."""
        self.ready = self._busy = self._ending = False
        self._last_zero_s = -math.inf
        serve = asyncio.create_task(self._serve(link, stop))
        watchdog = asyncio.create_task(self._watchdog(link, stop))
        stopping: asyncio.Future[Any] = asyncio.create_task(stop.wait())
        try:
            ready_by = time.monotonic() + READY_TIMEOUT_S
            while True:
                timeout = None if self.ready else max(0.0, ready_by - time.monotonic())
                done, _ = await asyncio.wait(
                    {serve, stopping}, timeout=timeout, return_when=asyncio.FIRST_COMPLETED
                )
                if serve in done:
                    serve.result()  # raises what ended the link (Lost, a DriveError)
                    if not stop.is_set():
                        raise Lost("the link ended")
                if stopping in done or serve in done:
                    break
                if not self.ready:  # not ready in time
                    if self.connections == 1:
                        raise DriveError(link.not_ready())
                    ready_by = time.monotonic() + READY_TIMEOUT_S
        finally:
            self._ending = True
            stopping.cancel()
            watchdog.cancel()
            if not self._busy:  # waiting for the link: nothing is half done
                serve.cancel()
            # (else the event being handled is finished first, a command sent is recorded)
            for task in (serve, stopping, watchdog):
                with suppress(asyncio.CancelledError, Exception):
                    await task
            if self.ready:
                with suppress(Lost):  # every exit with an open link stops the robot first
                    await self._send_zero(link, source="stop")
            self.ready = False
            await link.close()

    async def _serve(self, link: Link, stop: asyncio.Event) -> None:
        """Hand each event of the link on as it comes, in this one task (no hop per message)."""
        async for ev in link:
            self._busy = True
            try:
                if isinstance(ev, Ready):
                    await self._ready(link, ev)
                else:
                    await self._arrival(link, ev)
            finally:
                self._busy = False
            if stop.is_set() or self._ending:
                return

    async def _ready(self, link: Link, ev: Ready) -> None:
        self.ready = True
        self.command = ev.command
        if self.core is None:
            self._start_core(ev.camera)
        await self._send_zero(link, source="stale")  # a new link starts standing still

    def _start_core(self, camera: bool) -> None:
        inputs = Inputs(camera=camera)
        app = applicability(self.opts.table, inputs)
        check_applicable(app)
        self.app = app
        lacking = ", ".join(f"{b} (no {why})" for b, why in app.missing.items())
        self.notify(f"behaviours: {', '.join(app.have)}" + (f"; inapplicable: {lacking}" if lacking else ""))
        self.core = DriveCore(table=self.opts.table, limits=self.limits, inputs=inputs)
        if self.log is not None:
            self.recorder = LiveRecorder(self.log, self.core, shadow=self.opts.shadow)
        # everything loaded so far (type stores, the table, numpy) lives as long as the run: out of
        # the collector's way, so a full collection does not stall a tick
        gc.freeze()

    async def _arrival(self, link: Link, ev: Arrival) -> None:
        core, rec = self.core, ev.record
        if core is None:
            return
        if ev.role is Role.SCAN:
            assert isinstance(rec, LiveScan)
            res = core.scan(rec, time.monotonic())
            if isinstance(res, Skip):
                if res.warn:
                    self.warn(res.reason, res.reason)
                return
            if self._can_send():
                await link.send(*res.network, rec.record.t_ns)
                self.sent += 1
            self._robot_clock = (rec.record.t_ns, time.monotonic())
            latency = (time.perf_counter() - ev.arrived_s) * 1e3
            self.latencies.append(latency)
            self.cpu.append((time.thread_time() - ev.cpu_s) * 1e3)
            if self._blind_noted:
                self.notify("scans are back: driving")
                self._blind_noted = False
            if self.recorder is not None:
                self.recorder.tick(res, wall_s=time.monotonic(), latency_ms=latency)
            self._status()
        elif ev.role is Role.ODOM:
            assert isinstance(rec, LiveOdom)
            last = self._last_odom
            if last is not None:
                step = math.hypot(rec.x - last.x, rec.y - last.y)
                self.odometry_m += step if step < 1.0 else 0.0  # a reset odometry jumps
            self._last_odom = rec
            core.on_odom(rec)
        elif ev.role is Role.TF:
            assert isinstance(rec, LiveTf)
            core.on_tf(rec)
        elif ev.role is Role.TARGETS:
            assert isinstance(rec, LiveTargets)
            core.on_targets(rec)
        elif ev.role is Role.CMD:
            assert isinstance(rec, LiveTwist)
            core.on_robot_cmd(rec)

    def _can_send(self) -> bool:
        return self.ready and not self.opts.shadow

    def _status(self) -> None:
        now = time.monotonic()
        if not self.opts.shadow or now - self._last_status < STATUS_PERIOD_S or self.core is None:
            return
        self._last_status = now
        a = self.core.agreement
        if a.errors_deg:
            self.notify(
                f"agreement so far: {a.mean_deg:.1f}° mean heading error over {len(a.errors_deg)} ticks"
            )

    async def _send_zero(self, link: Link, *, source: str) -> None:
        if not self._can_send():
            return
        await link.send(0.0, 0.0, self._robot_now_ns())
        self.sent += 1
        self.zeros += 1
        if self.recorder is not None:
            self.recorder.zero(wall_s=time.monotonic(), source=source)

    async def _watchdog(self, link: Link, stop: asyncio.Event) -> None:
        while not stop.is_set():
            await asyncio.sleep(WATCHDOG_PERIOD_S)
            core = self.core
            if core is None or not self._can_send():
                continue
            now = time.monotonic()
            if core.watchdog.blind(now):
                if not self._blind_noted and core.watchdog.last_fresh_s is not None:
                    self.notify("no fresh scan for 0.5 s: stopping the robot until scans return")
                    self._blind_noted = True
                if now - self._last_zero_s < ZERO_PERIOD_S:
                    continue  # looks at 20 Hz, repeats the zero Twist at 10 Hz
                self._last_zero_s = now
                try:
                    await self._send_zero(link, source="stale")
                except Lost:
                    return

    # -- the run ----------------------------------------------------------------------------
    def _reconnected(self) -> None:
        if self.core is not None:
            self.core.reconnected()

    @property
    def connections(self) -> int:
        return self.links.connections

    async def run(self) -> str:
        return await self.links.run(self.connection, duration_s=self.opts.duration_s)


def run_live(
    opts: DriveOptions,
    transport: Transport,
    *,
    out: str | Path | None = None,
    notify: Notify = lambda _: None,
    stopper: Stopper | None = None,
) -> DriveSummary:
    """Run the table live on the robot ``transport`` reaches (see the module docstring); record ``out``."""
    if opts.duration_s is not None and not (opts.duration_s > 0 and math.isfinite(opts.duration_s)):
        raise DriveError("--duration must be a positive number of seconds")
    limits_of(opts.table.estimated_by, max_speed=opts.max_speed, max_turn=opts.max_turn)  # before any output
    stopper = stopper or Stopper()
    meta = {
        "tool": "lfdfuse",
        "version": __version__,
        "command": opts.command,
        "teacher": "drive:shadow" if opts.shadow else f"network:{opts.table_name}",
        "table": opts.table_name,
        "behaviors": ",".join(opts.table.behaviors),
        "connect": opts.url,
        "shadow": str(opts.shadow).lower(),
        "scan_topic": opts.scan_topic,
        "odom_topic": opts.odom_topic,
        "cmd_topic": opts.cmd_topic,
    }
    t0 = time.monotonic()
    ctx = LogWriter(out, metadata=meta) if out is not None else nullcontext(None)
    with ctx as log:
        s = _Session(opts, transport=transport, notify=notify, log=log, stopper=stopper)
        ended = asyncio.run(s.run())
        core = s.core
        lat = (_p(s.latencies, 50), _p(s.latencies, 99)) if s.latencies else None
        agree = core.agreement if core is not None else None
        if s.recorder is not None:
            s.recorder.close()
        if log is not None:
            log.metadata.update(
                {
                    "ended": ended,
                    "v_max_mps": repr(s.limits.v_max_mps),
                    "omega_max_rps": repr(s.limits.omega_max_rps),
                    "limits_from": s.limits_from,
                    "ticks": str(s.recorder.ticks if s.recorder else 0),
                    "commands_sent": str(s.sent),
                }
            )
            if lat is not None:
                log.metadata["latency_p50_ms"] = f"{lat[0]:.3f}"
                log.metadata["latency_p99_ms"] = f"{lat[1]:.3f}"
            if core is not None and core.frame is not None and core.mount is not None:
                m = core.mount
                log.metadata["laser_mount"] = ",".join(repr(round(v, 6)) for v in (m.x_m, m.y_m, m.yaw_rad))
                log.metadata["laser_mount_from"] = core.mount_from
                log.metadata["laser_max_range_m"] = repr(core.frame.geometry.max_range_m)
            if agree is not None and agree.errors_deg:
                log.metadata["agreement_heading_error_deg"] = f"{agree.mean_deg:.3f}"
    return DriveSummary(
        ticks=len(s.latencies),
        sent=s.sent,
        zeros=s.zeros,
        connections=s.connections,
        duration_s=time.monotonic() - t0,
        latency_ms=lat,
        latencies_ms=tuple(s.latencies),
        cpu_ms=tuple(s.cpu),
        agreement_deg=agree.mean_deg if agree is not None and agree.errors_deg else None,
        agreement_ticks=len(agree.errors_deg) if agree is not None else 0,
        odometry_m=s.odometry_m,
        ended=ended,
        encoding="" if opts.shadow else s.command,
        limits=s.limits,
        limits_from=s.limits_from,
        mount_from=core.mount_from if core is not None else "",
        behaviors=s.app,
        warnings=dict(s.warned),
        out=str(out) if out is not None else "",
    )
