"""What every ``/lfd/*`` codec shares: :class:`Codec` (JSON bytes in and out, the field check)
and the checks its decoders make of what the schemas in ``schemas/`` state.

orjson only ever yields dict, list, str, int, float, bool and None, and refuses NaN and numbers
that overflow a double, so exact ``type`` tests are both sufficient and fast. Every failed check
raises :class:`MessageError` saying what is wrong; the reader says where.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar, Self

import orjson

from lfdfuse.errors import LogError


class MessageError(LogError):
    """A ``/lfd/*`` message that breaks its schema; the message says what, the reader says where."""


def json_object(data: bytes) -> dict[str, Any]:
    try:
        msg = orjson.loads(data)
    except orjson.JSONDecodeError as exc:
        raise MessageError(f"not valid JSON ({str(exc)[:60]})") from None
    if type(msg) is not dict:
        raise MessageError("not a JSON object")
    return msg


def check_fields(msg: dict[str, Any], keys: frozenset[str]) -> None:
    """The schema's required fields and no others (``additionalProperties: false``).

    Only the count is compared here (cheap, once per message); a decoder that then misses a
    field calls :func:`keys_error` on the ``KeyError``.
    """
    if len(msg) != len(keys):
        raise keys_error(msg, keys)


def keys_error(msg: dict[str, Any], keys: frozenset[str]) -> MessageError:
    missing = sorted(keys - msg.keys())
    extra = sorted(map(str, msg.keys() - keys))
    if missing:
        return MessageError(f"a field is missing: {missing[0]!r}")
    if extra:
        return MessageError(f"an unknown field: {extra[0]!r:.40}")
    return MessageError("a field is missing")


def timestamp_ns(msg: dict[str, Any]) -> int:
    ts = msg["timestamp"]
    sec = ts.get("sec") if type(ts) is dict else None
    nsec = ts.get("nsec") if type(ts) is dict else None
    if type(sec) is int and type(nsec) is int and sec >= 0 and 0 <= nsec < 1_000_000_000:
        return sec * 1_000_000_000 + nsec
    raise MessageError("timestamp needs integer sec >= 0 and nsec in [0, 1e9)")


def as_number(v: object, what: str) -> float:
    if type(v) is float:
        if not math.isfinite(v):  # only from a dict not parsed by orjson
            raise MessageError(f"{what} is not finite")
        return v
    if type(v) is int:
        try:
            return float(v)  # always finite from orjson (its integers fit in 64 bits)
        except OverflowError:  # e.g. 10**400 from another parser
            raise MessageError(f"{what} is too large for a float") from None
    raise MessageError(f"{what} is not a number")


def as_flag(v: object, what: str) -> bool:
    if type(v) is not bool:
        raise MessageError(f"{what} is not true or false")
    return v


def as_count(v: object, what: str) -> int:
    if type(v) is not int or v < 0:
        raise MessageError(f"{what} is not a non-negative integer")
    return v


def as_name(v: object, what: str) -> str:
    if type(v) is not str:
        raise MessageError(f"{what} is not a string")
    return v


def as_name_or_none(v: object, what: str) -> str | None:
    return None if v is None else as_name(v, f"{what} (string or null)")


def as_names(v: object, what: str) -> tuple[str, ...]:
    if type(v) is not list:
        raise MessageError(f"{what} is not a list")
    if not set(map(type, v)) <= {str}:
        raise MessageError(f"an entry of {what} is not a string")
    return tuple(v)


class Codec:
    """What every ``/lfd/*`` message class shares: JSON bytes in and out, and the field check."""

    TOPIC: ClassVar[str]
    SCHEMA: ClassVar[str]
    KEYS: ClassVar[frozenset[str]]

    def to_dict(self) -> dict[str, Any]:
        raise NotImplementedError

    def encode(self) -> bytes:
        """The message's JSON bytes, as written to the MCAP."""
        return orjson.dumps(self.to_dict())

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> Self:
        raise NotImplementedError

    @classmethod
    def from_dict(cls, msg: dict[str, Any]) -> Self:
        """The message of a parsed JSON object; :class:`MessageError` if it breaks the schema."""
        if type(msg) is not dict:
            raise MessageError("not a JSON object")
        try:
            return cls._from_json(msg)
        except KeyError:
            raise keys_error(msg, cls.KEYS) from None

    @classmethod
    def decode(cls, data: bytes) -> Self:
        """The message of its JSON bytes; :class:`MessageError` if they break the schema."""
        msg = json_object(data)
        try:
            return cls._from_json(msg)
        except KeyError:
            raise keys_error(msg, cls.KEYS) from None


def as_choice(v: object, allowed: tuple[str, ...], what: str) -> str:
    if type(v) is not str or v not in allowed:
        raise MessageError(f"{what} is not one of {', '.join(allowed)}")
    return v
