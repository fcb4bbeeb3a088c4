"""``/lfd/command`` (DESIGN §15): what ``drive`` commanded each tick, in the ``/lfd/*`` codec family.

:class:`DriveCommand` is ``lfdfuse.DriveCommand``: the network's command of one tick (or a zero
Twist of the watchdog or of the exit), whether it was sent, the scan → command latency and,
in ``--shadow``, the heading error against the robot's own command. Commands are rounded to
1e-6 and the two times to 1e-4 on the wire, so a decoded message holds the rounded values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from lfdfuse.log.codec import (
    Codec,
    MessageError,
    as_choice,
    as_flag,
    as_number,
    check_fields,
    timestamp_ns,
)
from lfdfuse.log.stamps import stamp

#: network: from a fresh scan; stale: the watchdog's zero Twist; stop: the zero Twist on exit
COMMAND_SOURCES = ("network", "stale", "stop")

#: the channel ``drive`` adds (a contract)
DRIVE_TOPICS: dict[str, str] = {"/lfd/command": "lfdfuse.DriveCommand"}


def _one_field(msg: dict[str, Any], key: str, field: str) -> float:
    obj = msg[key]
    if type(obj) is not dict:
        raise MessageError(f"{key} is not an object")
    return as_number(obj[field], f"{key}.{field}")


def _number_or_none(v: object, what: str) -> float | None:
    return None if v is None else as_number(v, f"{what} (number or null)")


def _round(v: float | None, digits: int) -> float | None:
    return None if v is None else round(v, digits)


@dataclass(frozen=True)
class DriveCommand(Codec):
    """``lfdfuse.DriveCommand`` (see the module docstring)."""

    TOPIC: ClassVar[str] = "/lfd/command"
    SCHEMA: ClassVar[str] = "lfdfuse.DriveCommand"
    KEYS: ClassVar[frozenset[str]] = frozenset(
        {"timestamp", "linear", "angular", "source", "sent", "latency_ms", "heading_error_deg"}
    )

    t_ns: int
    v_mps: float
    omega_rps: float
    source: str
    sent: bool
    latency_ms: float | None = None
    heading_error_deg: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "timestamp": stamp(self.t_ns),
            "linear": {"x": round(self.v_mps, 6)},
            "angular": {"z": round(self.omega_rps, 6)},
            "source": self.source,
            "sent": self.sent,
            "latency_ms": _round(self.latency_ms, 4),
            "heading_error_deg": _round(self.heading_error_deg, 4),
        }

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> DriveCommand:
        check_fields(msg, cls.KEYS)
        return cls(
            timestamp_ns(msg),
            _one_field(msg, "linear", "x"),
            _one_field(msg, "angular", "z"),
            as_choice(msg["source"], COMMAND_SOURCES, "source"),
            as_flag(msg["sent"], "sent"),
            _number_or_none(msg["latency_ms"], "latency_ms"),
            _number_or_none(msg["heading_error_deg"], "heading_error_deg"),
        )
