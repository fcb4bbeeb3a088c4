"""What a person did, and its ``/teleop/input`` message (``lfdfuse.TeleopInput``, DESIGN §5).

Every input source — the terminal, a Foxglove client, a script — hands the session
:class:`Input` items; the session records each one, with the command it set, on
``/teleop/input``. The encoder and the decoder of that message sit side by side here.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any, Literal, Protocol

from lfdfuse.log.stamps import from_stamp, stamp

TOPIC = "/teleop/input"
SCHEMA = "lfdfuse.TeleopInput"

Kind = Literal["key", "message", "end", "handback"]


@dataclass(frozen=True)
class Input:
    """One key press (``kind="key"``, ``text`` a key name such as ``"i"`` or ``"up"``), one
    client message (``kind="message"``, ``text`` its JSON payload, ``schema`` its schema name),
    an end request (``kind="end"``, ``text`` why), or, when a network drives and the person
    corrects (``teleop --table``), a hand-back of control to the network (``kind="handback"``)."""

    kind: Kind
    text: str
    source: str = ""  # "keyboard", "foxglove client 3", "script"
    schema: str = ""


class InputSource(Protocol):
    """Anything the session polls once per control period for new inputs.

    ``t_s`` is the session's time since the start (wall clock, or simulated for scripts).
    """

    def poll(self, t_s: float) -> list[Input]: ...


class TwistError(ValueError):
    """A client message that is not a usable Twist."""


def parse_twist(payload: bytes | str) -> tuple[float, float]:
    """``(linear.x m/s, angular.z rad/s)`` of a JSON ``geometry_msgs/Twist`` (ROS 1 or 2 name).

    Missing fields count as 0 (as in ROS); a ``TwistStamped``-like ``{"twist": {...}}`` is
    accepted. Anything else raises :class:`TwistError`.

    >>> parse_twist(b'{"linear": {"x": 1, "y": 0, "z": 0}, "angular": {"x": 0, "y": 0, "z": -1}}')
    (1.0, -1.0)
    >>> parse_twist('{"angular": {"z": 0.5}}')
    (0.0, 0.5)
    """
    try:
        msg = json.loads(payload)
    except (ValueError, UnicodeDecodeError) as exc:
        raise TwistError(f"not JSON ({exc.__class__.__name__})") from None
    if isinstance(msg, dict) and "linear" not in msg and "angular" not in msg and "twist" in msg:
        msg = msg["twist"]
    if not isinstance(msg, dict):
        raise TwistError("not a JSON object")
    v = _component(msg, "linear", "x")
    w = _component(msg, "angular", "z")
    return v, w


def _component(msg: dict[str, Any], vec: str, axis: str) -> float:
    part = msg.get(vec, {})
    if not isinstance(part, dict):
        raise TwistError(f"{vec} is not an object")
    value = part.get(axis, 0.0)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TwistError(f"{vec}.{axis} is not a number")
    if not math.isfinite(value):
        raise TwistError(f"{vec}.{axis} is not finite")
    return float(value)


def teleop_input(
    t_ns: int, inp: Input, *, effect: str, command: tuple[float, float], wall_s: float
) -> dict[str, Any]:
    """An ``lfdfuse.TeleopInput``: the input, what it did, and the command held after it."""
    return {
        "timestamp": stamp(t_ns),
        "source": inp.source,
        "kind": inp.kind,
        "input": inp.text,
        "schema": inp.schema,
        "effect": effect,
        "v_mps": command[0],
        "omega_rps": command[1],
        "wall_s": round(wall_s, 3),
    }


@dataclass(frozen=True)
class TeleopInputMessage:
    """A decoded ``/teleop/input`` message."""

    t_ns: int
    source: str
    kind: str
    input: str
    effect: str
    command: tuple[float, float]


def decode_teleop_input(msg: dict[str, Any]) -> TeleopInputMessage:
    """Inverse of :func:`teleop_input`."""
    return TeleopInputMessage(
        from_stamp(msg["timestamp"]),
        msg["source"],
        msg["kind"],
        msg["input"],
        msg["effect"],
        (float(msg["v_mps"]), float(msg["omega_rps"])),
    )
