"""Time stamps, frames and planar rotations as the messages carry them.

Times are integer nanoseconds (epoch stamps of real logs included); ``{sec, nsec}`` on the wire.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from lfdfuse.errors import LogError

MAP_FRAME = "map"
ROBOT_FRAME = "base_link"


def stamp(t_ns: int) -> dict[str, int]:
    return {"sec": t_ns // 1_000_000_000, "nsec": t_ns % 1_000_000_000}


#: the int64 nanoseconds our arrays hold
MIN_T_NS, MAX_T_NS = -(2**63), 2**63 - 1


def check_log_time(path: str | Path, topic: str, t_ns: int) -> int:
    """``t_ns``, a message's log time, when our int64 arrays hold it (MCAP allows uint64); else a
    :class:`LogError` naming the file and topic."""
    if t_ns > MAX_T_NS:
        raise LogError(
            f"{path}: a {topic} message has log time {t_ns} ns, past the int64 nanoseconds lfdfuse reads"
        )
    return t_ns


def _whole(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"a stamp's sec and nsec must be integers, got {str(value)[:40]!r}")
    if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
        raise ValueError(f"a stamp's sec and nsec must be integers, got {value!r}")
    return int(value)


def from_stamp(d: dict[str, Any]) -> int:
    """``{sec, nsec}`` as integer nanoseconds; :class:`ValueError` when not integers or past int64.

    >>> from_stamp(stamp(1_700_000_000_123_456_789))
    1700000000123456789
    >>> from_stamp({"sec": 2**64, "nsec": 0})
    Traceback (most recent call last):
    ...
    ValueError: a stamp of 18446744073709551616 s is past the int64 nanoseconds lfdfuse reads
    """
    sec, nsec = _whole(d["sec"]), _whole(d["nsec"])
    t = sec * 1_000_000_000 + nsec
    if not MIN_T_NS <= t <= MAX_T_NS:
        raise ValueError(f"a stamp of {sec} s is past the int64 nanoseconds lfdfuse reads")
    return t


def quat_z(theta: float) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(theta / 2), "w": math.cos(theta / 2)}


def yaw_of(q: dict[str, float]) -> float:
    return math.atan2(2 * (q["w"] * q["z"] + q["x"] * q["y"]), 1 - 2 * (q["y"] ** 2 + q["z"] ** 2))


IDENTITY_POSE = {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": quat_z(0.0)}
