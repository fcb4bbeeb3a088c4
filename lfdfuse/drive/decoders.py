"""The one registry of what ``drive`` can read: (message encoding, schema name) → role and decoder.

Every transport asks it the same two questions of a channel it discovers: :func:`role_of`
(is it a scan, odometry, tf, a command, target detections — or nothing we read?) and
:func:`decoder_for` (bytes → our record, or :class:`~lfdfuse.drive.decode.DecodeError`). Two
families are registered here: CDR with ``ros2msg`` schemas (what ``foxglove_bridge`` and a
ROS 2 robot send; the type store is built from the schema text the channel carries, the
standard ROS 2 one when it carries none) and lfdfuse's own JSON. The conversions into records
are :mod:`lfdfuse.drive.decode`'s; this module only says which reads which.

A new message type is one :func:`register` call: the role, and a factory that makes the
decoder from the channel's schema text.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import orjson

from lfdfuse.drive.decode import (
    TWIST,
    TWIST_STAMPED,
    DecodeError,
    Decoder,
    Record,
    Role,
    _cdr_odom,
    _cdr_scan,
    _cdr_tf,
    _cdr_twist,
    _json_pose,
    _json_scan,
    _json_targets,
    _json_tf,
    _json_twist,
    typestore_for,
)

#: a decoder from the channel's schema name and schema text
MakeDecoder = Callable[[str, str], Decoder]


class Described(Protocol):
    """A channel as a transport discovered it."""

    @property
    def topic(self) -> str: ...
    @property
    def encoding(self) -> str: ...
    @property
    def schema_name(self) -> str: ...
    @property
    def schema(self) -> str: ...


@dataclass(frozen=True)
class Entry:
    role: Role
    make: MakeDecoder


REGISTRY: dict[tuple[str, str], Entry] = {}


def register(encoding: str, schema_name: str, role: Role, make: MakeDecoder) -> None:
    """``encoding`` messages of type ``schema_name`` are ``role``, decoded by ``make(name, text)``."""
    REGISTRY[(encoding, schema_name)] = Entry(role, make)


def role_of(ch: Described) -> Role | None:
    """What the channel is to ``drive`` (None: nothing it reads)."""
    entry = REGISTRY.get((ch.encoding, ch.schema_name))
    return entry.role if entry is not None else None


def decoder_for(ch: Described) -> Decoder:
    """The channel's decoder; :class:`DecodeError` when none is registered or its schema is bad."""
    entry = REGISTRY.get((ch.encoding, ch.schema_name))
    if entry is None:
        raise DecodeError(f"{ch.topic}: no decoder for {ch.encoding} {ch.schema_name}")
    return entry.make(ch.schema_name, ch.schema)


# -- the two families ---------------------------------------------------------------------------


def cdr(read: Callable[[Any], Record]) -> MakeDecoder:
    """CDR read with the type store of the channel's ``ros2msg`` schema, then ``read`` into a record."""

    def make(name: str, schema: str) -> Decoder:
        store = typestore_for(name, schema)

        def decode(data: bytes) -> Record:
            try:
                return read(store.deserialize_cdr(data, name))
            except DecodeError:
                raise
            except Exception as exc:  # a truncated or foreign payload fails anywhere in the generated code
                raise DecodeError(f"undecodable {name} ({exc.__class__.__name__})") from None

        return decode

    return make


def json_message(read: Callable[[dict[str, Any]], Record]) -> MakeDecoder:
    """A JSON object, then ``read`` into a record."""

    def make(name: str, schema: str) -> Decoder:
        def decode(data: bytes) -> Record:
            try:
                return read(orjson.loads(data))
            except DecodeError:
                raise
            except (
                orjson.JSONDecodeError,
                KeyError,
                TypeError,
                ValueError,
                IndexError,
                AttributeError,
            ) as exc:
                raise DecodeError(f"undecodable {name} ({exc.__class__.__name__})") from None

        return decode

    return make


def _raw(decode: Decoder) -> MakeDecoder:
    """A decoder that reads the bytes itself (whatever the schema)."""
    return lambda name, schema: decode


for _name, _role, _read in (
    ("sensor_msgs/msg/LaserScan", Role.SCAN, _cdr_scan),
    ("nav_msgs/msg/Odometry", Role.ODOM, _cdr_odom),
    ("tf2_msgs/msg/TFMessage", Role.TF, _cdr_tf),
    (TWIST, Role.CMD, _cdr_twist),
    (TWIST_STAMPED, Role.CMD, _cdr_twist),
):
    register("cdr", _name, _role, cdr(_read))

for _name, _role, _read_json in (
    ("foxglove.LaserScan", Role.SCAN, _json_scan),
    ("foxglove.PoseInFrame", Role.ODOM, _json_pose),
    ("foxglove.FrameTransform", Role.TF, _json_tf),
    ("lfdfuse.TargetDetections", Role.TARGETS, _json_targets),
):
    register("json", _name, _role, json_message(_read_json))

for _name in ("geometry_msgs/Twist", TWIST, TWIST_STAMPED, "lfdfuse.Twist"):
    register("json", _name, Role.CMD, _raw(_json_twist))
