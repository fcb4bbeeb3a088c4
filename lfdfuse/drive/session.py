"""The socket shell of ``lfdfuse drive``: connect, subscribe, publish, reconnect, stop safely.

:func:`drive` runs one live session against a Foxglove WebSocket server (``foxglove_bridge``
on a robot, or ``lfdfuse teleop --input foxglove``) until ``--duration``, a signal
(SIGINT/SIGTERM) or :meth:`Stopper.stop`. Per connection: the server's ``serverInfo`` picks the
encoding of our Twist (CDR when it takes it, else JSON); its ``advertise`` messages name the
channels, of which it subscribes the scan, the odometry, tf, a camera's targets and, in
``--shadow``, the robot's own command; once the scan is advertised it advertises the command
channel — ``geometry_msgs/msg/TwistStamped`` when the server advertises the command topic with
that type, else ``Twist`` (not in ``--shadow``: nothing is published). Each scan frame is decoded, handed to the
:class:`~lfdfuse.drive.core.DriveCore` and its command sent at once, in the same task — the
scan → command latency is decoding plus one network tick. A watchdog task sends a zero Twist
every period while no fresh scan came for 0.5 s. Every exit path with an open connection sends
a zero Twist first; a lost connection is retried with back-off while the duration lasts, and
nothing is sent while it is down. The library never prints: ``notify`` gets one-line notes.
"""

from __future__ import annotations

import asyncio
import gc
import math
import signal
import socket
import time
from collections import Counter
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import websockets
from websockets.exceptions import ConnectionClosed, InvalidHandshake, InvalidURI

from lfdfuse import __version__
from lfdfuse.drive import wire
from lfdfuse.drive.channels import Subscriptions, Topics
from lfdfuse.drive.core import Applicability, DriveCore, Inputs, Skip, applicability, check_applicable
from lfdfuse.drive.decode import (
    DecodeError,
    LiveOdom,
    LiveScan,
    LiveTargets,
    LiveTf,
    LiveTwist,
    Role,
    TwistEncoder,
    twist_encoder,
)
from lfdfuse.drive.options import DriveError, DriveOptions, DriveSummary, Notify, Stopper
from lfdfuse.drive.record import LiveRecorder
from lfdfuse.drive.safety import WATCHDOG_PERIOD_S, limits_of
from lfdfuse.log.writer import LogWriter

#: the first connection must open within this (a later one is retried while --duration lasts)
CONNECT_TIMEOUT_S = 3.0
#: how long after connecting the scan channel must be advertised
ADVERTISE_TIMEOUT_S = 3.0
BACKOFF_S = (0.2, 2.0)  # first retry delay, the longest
STATUS_PERIOD_S = 5.0
ZERO_PERIOD_S = 0.1  # the zero Twist's repeat while blind
_OUR_CHANNEL = 1


class _Lost(Exception):
    """The connection dropped (retried)."""


def _p(values: list[float], q: float) -> float:
    return float(np.percentile(np.asarray(values), q))


class _Session:
    def __init__(
        self, opts: DriveOptions, *, notify: Notify, log: LogWriter | None, stopper: Stopper
    ) -> None:
        self.opts = opts
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
        self._arrived_cpu = 0.0
        self.sent = self.zeros = self.connections = 0
        self.warned: Counter[str] = Counter()
        self.encoder: TwistEncoder | None = None
        self.odometry_m = 0.0
        self._last_odom: LiveOdom | None = None
        self._blind_noted = False
        self._last_status = 0.0
        self._robot_clock: tuple[int, float] | None = None  # (stamp, monotonic s) of the last tick

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

    # -- one connection ---------------------------------------------------------------------
    async def connection(self, ws: Any, stop: asyncio.Event) -> None:
        """Serve one open connection until ``stop`` or the connection drops (:class:`_Lost`)."""
        o = self.opts
        st = _Conn(Subscriptions(Topics(o.scan_topic, o.odom_topic, o.cmd_topic, o.shadow)))
        watchdog = asyncio.create_task(self._watchdog(ws, st, stop))
        try:
            advertised_by = time.monotonic() + ADVERTISE_TIMEOUT_S
            recv: asyncio.Task[Any] | None = None
            stopping = asyncio.create_task(stop.wait())
            while not stop.is_set():
                recv = asyncio.ensure_future(ws.recv())
                timeout = None if st.subs.scan else max(0.0, advertised_by - time.monotonic())
                done, _ = await asyncio.wait(
                    {recv, stopping}, timeout=timeout, return_when=asyncio.FIRST_COMPLETED
                )
                if stopping in done:
                    recv.cancel()
                    break
                if recv not in done:
                    recv.cancel()
                    if self.connections == 1:
                        names = ", ".join(st.subs.advertised_topics()) or "none"
                        raise DriveError(
                            f"the server advertises no scan on {self.opts.scan_topic} (it has: {names})"
                        )
                    advertised_by = time.monotonic() + ADVERTISE_TIMEOUT_S
                    continue
                try:
                    frame = recv.result()
                except ConnectionClosed as exc:
                    raise _Lost(str(exc)) from None
                arrived, self._arrived_cpu = time.perf_counter(), time.thread_time()
                quick_ack(ws)
                await self._frame(ws, st, frame, arrived)
            stopping.cancel()
        finally:
            watchdog.cancel()
            try:
                await watchdog
            except (asyncio.CancelledError, _Lost):
                pass
            if st.advertised:
                try:  # every exit with an open connection stops the robot first
                    await self._send_zero(ws, st, source="stop")
                    await ws.send(wire.unadvertise(_OUR_CHANNEL))
                except ConnectionClosed:
                    pass

    async def _frame(self, ws: Any, st: _Conn, frame: str | bytes, arrived: float) -> None:
        try:
            ev = wire.parse_frame(frame)
        except wire.WireError as exc:
            self.warn("wire", f"{exc}; ignored")
            return
        if isinstance(ev, wire.MessageData):
            sub = st.subs.subs.get(ev.subscription)
            if sub is None:
                return
            try:
                rec = sub.decode(ev.payload)
            except DecodeError as exc:
                self.warn(f"decode {sub.topic}", f"{sub.topic}: {exc}; ignored (further ones counted)")
                return
            await self._record(ws, st, sub.role, rec, arrived)
        elif isinstance(ev, wire.ServerInfo):
            st.info = ev
            if not self.opts.shadow:
                try:
                    twist_encoder(ev.encodings)  # can we send at all? (the type is chosen later)
                except DecodeError as exc:
                    raise DriveError(str(exc)) from None
                if "clientPublish" not in ev.capabilities:
                    raise DriveError(
                        f"the server {ev.name!r} does not accept client publishing (clientPublish)"
                    )
        elif isinstance(ev, list):
            await self._advertised(ws, st, ev)
        elif isinstance(ev, wire.Unadvertise):
            st.subs.unadvertised(ev.ids)
        elif isinstance(ev, wire.Status) and ev.level >= 1:
            self.warn(f"status {ev.message}", f"the server says: {ev.message}")

    async def _advertised(self, ws: Any, st: _Conn, channels: list[wire.ServerChannel]) -> None:
        pairs, warnings = st.subs.advertised(channels)
        for text in warnings:
            self.warn(text, text)
        if pairs:
            await ws.send(wire.subscribe(pairs))
        if st.subs.scan and self.core is None:
            self._start_core(st)
        if st.subs.scan and not self.opts.shadow and not st.advertised and st.info is not None:
            enc = self.encoder = twist_encoder(st.info.encodings, stamped=st.subs.stamped_cmd())
            await ws.send(
                wire.advertise(
                    channel_id=_OUR_CHANNEL,
                    topic=self.opts.cmd_topic,
                    encoding=enc.encoding,
                    schema_name=enc.schema_name,
                    schema=enc.schema,
                )
            )
            st.advertised = True
            await self._send_zero(ws, st, source="stale")  # a new connection starts standing still

    def _start_core(self, st: _Conn) -> None:
        inputs = Inputs(camera=st.subs.camera)
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

    async def _record(self, ws: Any, st: _Conn, role: Role, rec: Any, arrived: float) -> None:
        core = self.core
        if core is None:
            return
        if role is Role.SCAN:
            assert isinstance(rec, LiveScan)
            res = core.scan(rec, time.monotonic())
            if isinstance(res, Skip):
                if res.warn:
                    self.warn(res.reason, res.reason)
                return
            latency: float | None = None
            if not self.opts.shadow and st.advertised and self.encoder is not None:
                payload = self.encoder.encode(*res.network, rec.record.t_ns)
                await ws.send(wire.client_message(_OUR_CHANNEL, payload))
                self.sent += 1
            self._robot_clock = (rec.record.t_ns, time.monotonic())
            latency = (time.perf_counter() - arrived) * 1e3
            self.latencies.append(latency)
            self.cpu.append((time.thread_time() - self._arrived_cpu) * 1e3)
            if self._blind_noted:
                self.notify("scans are back: driving")
                self._blind_noted = False
            if self.recorder is not None:
                self.recorder.tick(res, wall_s=time.monotonic(), latency_ms=latency)
            self._status()
        elif role is Role.ODOM:
            assert isinstance(rec, LiveOdom)
            last = self._last_odom
            if last is not None:
                step = math.hypot(rec.x - last.x, rec.y - last.y)
                self.odometry_m += step if step < 1.0 else 0.0  # a reset odometry jumps
            self._last_odom = rec
            core.on_odom(rec)
        elif role is Role.TF:
            assert isinstance(rec, LiveTf)
            core.on_tf(rec)
        elif role is Role.TARGETS:
            assert isinstance(rec, LiveTargets)
            core.on_targets(rec)
        elif role is Role.CMD:
            assert isinstance(rec, LiveTwist)
            core.on_robot_cmd(rec)

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

    async def _send_zero(self, ws: Any, st: _Conn, *, source: str) -> None:
        if self.opts.shadow or not st.advertised or self.encoder is None:
            return
        await ws.send(wire.client_message(_OUR_CHANNEL, self.encoder.encode(0.0, 0.0, self._robot_now_ns())))
        self.sent += 1
        self.zeros += 1
        if self.recorder is not None:
            self.recorder.zero(wall_s=time.monotonic(), source=source)

    async def _watchdog(self, ws: Any, st: _Conn, stop: asyncio.Event) -> None:
        while not stop.is_set():
            await asyncio.sleep(WATCHDOG_PERIOD_S)
            core = self.core
            if core is None or self.opts.shadow or not st.advertised:
                continue
            now = time.monotonic()
            if core.watchdog.blind(now):
                if not self._blind_noted and core.watchdog.last_fresh_s is not None:
                    self.notify("no fresh scan for 0.5 s: stopping the robot until scans return")
                    self._blind_noted = True
                if now - st.last_zero_s < ZERO_PERIOD_S:
                    continue  # looks at 20 Hz, repeats the zero Twist at 10 Hz
                st.last_zero_s = now
                try:
                    await self._send_zero(ws, st, source="stale")
                except ConnectionClosed:
                    return

    # -- the run ----------------------------------------------------------------------------
    async def run(self) -> str:
        loop = asyncio.get_running_loop()
        stop = asyncio.Event()
        self.stopper.bind(loop, stop)
        if self.stopper.reason:
            stop.set()
        handlers: dict[signal.Signals, Any] = {}
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                previous = signal.getsignal(sig)
                loop.add_signal_handler(sig, self.stopper.stop, f"signal {sig.name}")
                handlers[sig] = previous
            except (RuntimeError, ValueError, NotImplementedError):
                pass  # not the main thread (a test): stop through the Stopper
        timer = None
        if self.opts.duration_s is not None:
            timer = loop.call_later(self.opts.duration_s, self.stopper.stop, "--duration")
        backoff = BACKOFF_S[0]
        first_by = time.monotonic() + CONNECT_TIMEOUT_S
        try:
            while not stop.is_set():
                try:
                    async with websockets.connect(
                        self.opts.url,
                        subprotocols=[websockets.Subprotocol(s) for s in wire.SUBPROTOCOLS],
                        max_size=None,
                        open_timeout=CONNECT_TIMEOUT_S,
                        ping_interval=1.0,
                        ping_timeout=2.0,
                        compression=None,
                    ) as ws:
                        self.connections += 1
                        backoff = BACKOFF_S[0]
                        if self.connections > 1:
                            self.notify(f"reconnected to {self.opts.url}")
                            if self.core is not None:
                                self.core.reconnected()
                        await self.connection(ws, stop)
                except InvalidURI as exc:
                    raise DriveError(f"--connect: not a WebSocket URL: {exc}") from None
                except (_Lost, ConnectionClosed, OSError, InvalidHandshake, TimeoutError) as exc:
                    if self.connections == 0 and time.monotonic() > first_by:
                        raise DriveError(f"cannot connect to {self.opts.url}: {_why(exc)}") from None
                    if self.connections > 0 and not stop.is_set():
                        self.warn(f"lost {self.connections}", f"connection lost ({_why(exc)}): reconnecting")
                if stop.is_set():
                    break
                try:  # back off, but wake at once on stop
                    await asyncio.wait_for(stop.wait(), timeout=backoff)
                except TimeoutError:
                    pass
                backoff = min(backoff * 2, BACKOFF_S[1])
        finally:
            if timer is not None:
                timer.cancel()
            for sig, previous in handlers.items():
                loop.remove_signal_handler(sig)
                signal.signal(sig, previous)  # the caller's (the CLI's SIGTERM → clean unwinding)
        return self.stopper.reason or "stopped"


@dataclass
class _Conn:
    """What one connection has learnt."""

    subs: Subscriptions
    info: wire.ServerInfo | None = None
    advertised: bool = False
    last_zero_s: float = -math.inf


def quick_ack(ws: Any) -> None:
    """Acknowledge at once what the server sent (Linux ``TCP_QUICKACK``; the kernel clears it again).

    A server that writes several small frames per scan without ``TCP_NODELAY`` (the Foxglove
    SDK's does) holds the scan back until its first frame is acknowledged — up to the 40 ms
    of a delayed ACK, every tick.
    """
    sock = ws.transport.get_extra_info("socket") if ws.transport is not None else None
    if sock is not None and _QUICKACK is not None:
        try:
            sock.setsockopt(socket.IPPROTO_TCP, _QUICKACK, 1)
        except OSError:
            pass


_QUICKACK: int | None = getattr(socket, "TCP_QUICKACK", None)


def _why(exc: BaseException) -> str:
    text = str(exc) or exc.__class__.__name__
    return text.splitlines()[0]


def drive(
    opts: DriveOptions,
    *,
    out: str | Path | None = None,
    notify: Notify = lambda _: None,
    stopper: Stopper | None = None,
) -> DriveSummary:
    """Run the table live against ``opts.url`` (see the module docstring); record ``out``."""
    if not opts.url.startswith(("ws://", "wss://")):
        raise DriveError(f"--connect must be a ws://HOST:PORT URL, got {opts.url!r}")
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
        s = _Session(opts, notify=notify, log=log, stopper=stopper)
        ended = asyncio.run(s.run())
        core = s.core
        lat = (_p(s.latencies, 50), _p(s.latencies, 99)) if s.latencies else None
        agree = core.agreement if core is not None else None
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
        encoding="" if opts.shadow or s.encoder is None else f"{s.encoder.encoding} {s.encoder.schema_name}",
        limits=s.limits,
        limits_from=s.limits_from,
        mount_from=core.mount_from if core is not None else "",
        behaviors=s.app,
        warnings=dict(s.warned),
        out=str(out) if out is not None else "",
    )
