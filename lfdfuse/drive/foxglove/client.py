"""The Foxglove WebSocket transport of ``drive``: ``foxglove_bridge`` on a robot, or ``lfdfuse teleop``.

Per connection: the server's ``serverInfo`` picks the encoding of our Twist (CDR when it
takes it, else JSON) and must offer ``clientPublish`` (not in ``--shadow``); its
``advertise`` messages name the channels, of which :mod:`~lfdfuse.drive.foxglove.channels`
subscribes the scan, the odometry, tf, a camera's targets and, in ``--shadow``, the robot's own
command. Once the scan is subscribed the link advertises the command channel —
``geometry_msgs/msg/TwistStamped`` when the server advertises the command topic with that type,
else ``Twist`` (not in ``--shadow``: nothing is published) — and is :class:`Ready`. Message
frames decode through :mod:`lfdfuse.drive.decoders`; an undecodable one is a warning (once per
topic) and is skipped.
"""

from __future__ import annotations

import socket
import time
from typing import Any, Self

import websockets
from websockets.exceptions import ConnectionClosed, InvalidHandshake, InvalidURI

from lfdfuse.drive.decode import DecodeError, TwistEncoder, twist_encoder
from lfdfuse.drive.foxglove import wire
from lfdfuse.drive.foxglove.channels import Subscriptions
from lfdfuse.drive.options import DriveError
from lfdfuse.drive.transport import Arrival, Event, Lost, Ready, Topics, Warn

_OUR_CHANNEL = 1


class FoxgloveTransport:
    """Links to the Foxglove WebSocket server at ``url`` (``ws://HOST:PORT``)."""

    def __init__(self, url: str, topics: Topics) -> None:
        self.url = url
        self.topics = topics

    async def connect(self, *, timeout_s: float, warn: Warn) -> FoxgloveLink:
        try:
            ws = await websockets.connect(
                self.url,
                subprotocols=[websockets.Subprotocol(s) for s in wire.SUBPROTOCOLS],
                max_size=None,
                open_timeout=timeout_s,
                ping_interval=1.0,
                ping_timeout=2.0,
                compression=None,
            )
        except InvalidURI as exc:
            raise DriveError(f"--connect: not a WebSocket URL: {exc}") from None
        except (OSError, InvalidHandshake, TimeoutError) as exc:
            raise Lost(_why(exc)) from None
        return FoxgloveLink(ws, self.topics, warn)


class FoxgloveLink:
    """One open WebSocket connection (see the module docstring)."""

    def __init__(self, ws: Any, topics: Topics, warn: Warn) -> None:
        self.ws = ws
        self.topics = topics
        self.warn = warn
        self.subs = Subscriptions(topics)
        self.info: wire.ServerInfo | None = None
        self.encoder: TwistEncoder | None = None
        self.advertised = False  # our command channel
        self.ready = False

    def __aiter__(self) -> Self:
        return self

    async def __anext__(self) -> Event:
        while True:
            try:
                frame = await self.ws.recv()
            except ConnectionClosed as exc:
                raise Lost(_why(exc)) from None
            arrived, cpu = time.perf_counter(), time.thread_time()
            quick_ack(self.ws)
            try:
                ev = await self._frame(frame, arrived, cpu)
            except ConnectionClosed as exc:
                raise Lost(_why(exc)) from None
            if ev is not None:
                return ev

    async def _frame(self, frame: str | bytes, arrived: float, cpu: float) -> Event | None:
        try:
            ev = wire.parse_frame(frame)
        except wire.WireError as exc:
            self.warn("wire", f"{exc}; ignored")
            return None
        if isinstance(ev, wire.MessageData):
            sub = self.subs.subs.get(ev.subscription)
            if sub is None:
                return None
            try:
                rec = sub.decode(ev.payload)
            except DecodeError as exc:
                self.warn(f"decode {sub.topic}", f"{sub.topic}: {exc}; ignored (further ones counted)")
                return None
            return Arrival(sub.role, rec, arrived, cpu)
        if isinstance(ev, wire.ServerInfo):
            self._server_info(ev)
        elif isinstance(ev, list):
            return await self._advertised(ev)
        elif isinstance(ev, wire.Unadvertise):
            self.subs.unadvertised(ev.ids)
        elif isinstance(ev, wire.Status) and ev.level >= 1:
            self.warn(f"status {ev.message}", f"the server says: {ev.message}")
        return None

    def _server_info(self, info: wire.ServerInfo) -> None:
        self.info = info
        if self.topics.shadow:
            return
        try:
            twist_encoder(info.encodings)  # can we send at all? (the type is chosen later)
        except DecodeError as exc:
            raise DriveError(str(exc)) from None
        if "clientPublish" not in info.capabilities:
            raise DriveError(f"the server {info.name!r} does not accept client publishing (clientPublish)")

    async def _advertised(self, channels: list[wire.ServerChannel]) -> Ready | None:
        pairs, warnings = self.subs.advertised(channels)
        for text in warnings:
            self.warn(text, text)
        if pairs:
            await self.ws.send(wire.subscribe(pairs))
        if not self.subs.scan:
            return None
        if not self.topics.shadow and not self.advertised and self.info is not None:
            enc = self.encoder = twist_encoder(self.info.encodings, stamped=self.subs.stamped_cmd())
            await self.ws.send(
                wire.advertise(
                    channel_id=_OUR_CHANNEL,
                    topic=self.topics.cmd,
                    encoding=enc.encoding,
                    schema_name=enc.schema_name,
                    schema=enc.schema,
                )
            )
            self.advertised = True
        if self.ready or not (self.topics.shadow or self.advertised):
            return None
        self.ready = True
        e = self.encoder
        return Ready(
            camera=self.subs.camera, command=f"{e.encoding} {e.schema_name}" if e is not None else ""
        )

    async def send(self, v_mps: float, omega_rps: float, stamp_ns: int) -> None:
        assert self.encoder is not None and self.advertised
        try:
            await self.ws.send(
                wire.client_message(_OUR_CHANNEL, self.encoder.encode(v_mps, omega_rps, stamp_ns))
            )
        except ConnectionClosed as exc:
            raise Lost(_why(exc)) from None

    def not_ready(self) -> str:
        names = ", ".join(self.subs.advertised_topics()) or "none"
        return f"the server advertises no scan on {self.topics.scan} (it has: {names})"

    def publishers(self, topic: str) -> tuple[str, ...]:
        return ()  # the protocol does not name them

    async def close(self) -> None:
        try:
            if self.advertised:
                await self.ws.send(wire.unadvertise(_OUR_CHANNEL))
            await self.ws.close()
        except (ConnectionClosed, OSError):
            pass


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
