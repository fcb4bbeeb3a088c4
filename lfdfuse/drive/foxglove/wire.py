"""The Foxglove WebSocket protocol (``foxglove.websocket.v1``), client side, as pure functions.

Text frames are JSON objects with an ``op``; binary frames start with an opcode byte. The
server sends ``serverInfo``, ``advertise``/``unadvertise`` and ``status`` as text, and message
data as binary ``0x01 | u32 subscription id | u64 log time ns | payload``. The client sends
``subscribe``, ``advertise`` (client channels, needs the ``clientPublish`` capability) as text
and its messages as binary ``0x01 | u32 client channel id | payload``. Integers are
little-endian. Nothing here touches a socket: the session hands frames in and sends what
these functions build.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Any

import orjson

#: what we offer in the handshake: foxglove_bridge speaks the first, the Foxglove SDK's
#: server (lfdfuse teleop) only accepts the second
SUBPROTOCOLS = ("foxglove.websocket.v1", "foxglove.sdk.v1")
MESSAGE_DATA = 0x01
_HEAD = struct.Struct("<BIQ")
_CLIENT_HEAD = struct.Struct("<BI")


class WireError(ValueError):
    """A frame that does not follow the protocol."""


@dataclass(frozen=True)
class ServerInfo:
    name: str
    capabilities: tuple[str, ...]
    encodings: tuple[str, ...]  # message encodings the server accepts from clients


@dataclass(frozen=True)
class ServerChannel:
    """An advertised channel: its id, topic, message encoding and schema (text)."""

    id: int
    topic: str
    encoding: str
    schema_name: str
    schema_encoding: str
    schema: str


@dataclass(frozen=True)
class Unadvertise:
    ids: tuple[int, ...]


@dataclass(frozen=True)
class Status:
    level: int
    message: str


@dataclass(frozen=True)
class MessageData:
    subscription: int
    log_time_ns: int
    payload: bytes


Event = ServerInfo | list[ServerChannel] | Unadvertise | Status | MessageData | None


def parse_frame(frame: str | bytes) -> Event:
    """One server frame as an event; None for an op we do not use. Raises :class:`WireError`."""
    if isinstance(frame, bytes):
        if len(frame) < _HEAD.size or frame[0] != MESSAGE_DATA:
            return None  # time (0x02), service responses …: not ours
        _, sub, t_ns = _HEAD.unpack_from(frame)
        return MessageData(sub, t_ns, frame[_HEAD.size :])
    try:
        msg = orjson.loads(frame)
        op = msg["op"]
        if op == "serverInfo":
            return ServerInfo(
                str(msg.get("name", "")),
                tuple(msg.get("capabilities", ())),
                tuple(msg.get("supportedEncodings") or ()),
            )
        if op == "advertise":
            return [_channel(c) for c in msg["channels"]]
        if op == "unadvertise":
            return Unadvertise(tuple(int(i) for i in msg["channelIds"]))
        if op == "status":
            return Status(int(msg.get("level", 0)), str(msg.get("message", "")))
    except (orjson.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
        raise WireError(f"malformed server frame ({exc.__class__.__name__}: {exc})") from None
    return None


def _channel(c: dict[str, Any]) -> ServerChannel:
    schema = c.get("schema", "")
    return ServerChannel(
        int(c["id"]),
        str(c["topic"]),
        str(c["encoding"]),
        str(c.get("schemaName", "")),
        str(c.get("schemaEncoding") or ""),
        schema if isinstance(schema, str) else "",
    )


def subscribe(pairs: list[tuple[int, int]]) -> str:
    """Subscribe ``(subscription id, channel id)`` pairs."""
    subs = [{"id": s, "channelId": c} for s, c in pairs]
    return orjson.dumps({"op": "subscribe", "subscriptions": subs}).decode()


def advertise(*, channel_id: int, topic: str, encoding: str, schema_name: str, schema: str) -> str:
    """Advertise one client channel (``schemaEncoding`` ros2msg for CDR, jsonschema for JSON)."""
    ch: dict[str, Any] = {"id": channel_id, "topic": topic, "encoding": encoding, "schemaName": schema_name}
    if schema:
        ch["schema"] = schema
        ch["schemaEncoding"] = "ros2msg" if encoding == "cdr" else "jsonschema"
    return orjson.dumps({"op": "advertise", "channels": [ch]}).decode()


def unadvertise(channel_id: int) -> str:
    return orjson.dumps({"op": "unadvertise", "channelIds": [channel_id]}).decode()


def client_message(channel_id: int, payload: bytes) -> bytes:
    """A client message on an advertised client channel."""
    return _CLIENT_HEAD.pack(MESSAGE_DATA, channel_id) + payload


def server_message(subscription: int, log_time_ns: int, payload: bytes) -> bytes:
    """A server message frame (the inverse of :func:`parse_frame`, for tests and test servers)."""
    return _HEAD.pack(MESSAGE_DATA, subscription, log_time_ns) + payload
