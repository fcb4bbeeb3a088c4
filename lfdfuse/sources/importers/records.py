"""What every importer yields: our own small records, nothing format-specific.

An importer (one module per source format) opens a log and exposes a :class:`Source`: a
:class:`SourceInfo` (format, topics picked, laser mounting, robot limits) and three generators of
records in the source's own time order: :class:`ScanRecord`, :class:`CommandRecord` and
:class:`PoseRecord`. Time stamps are int64 nanoseconds (epoch stamps stay exact); scans are in the
*sensor* frame, with every beam that has no return already set to ``inf``. Messages an importer
skips are counted by reason in ``Source.dropped``.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from lfdfuse.errors import LfdError


class SourceError(LfdError):
    """A robot log cannot be imported (unknown format, unreadable, missing topic)."""


@dataclass(frozen=True, eq=False)
class ScanRecord:
    """One planar laser scan in the sensor frame.

    Beam ``i`` points at ``start_rad + i·increment_rad`` (counter-clockwise, sensor frame);
    ``ranges_m (B,)`` float64 with ``inf`` for every beam without a return.
    """

    t_ns: int
    start_rad: float
    increment_rad: float
    ranges_m: np.ndarray
    max_range_m: float

    @property
    def count(self) -> int:
        return len(self.ranges_m)


@dataclass(frozen=True)
class CommandRecord:
    """A velocity command: forward speed (m/s) and turn rate (rad/s), held until the next one."""

    t_ns: int
    v_mps: float
    omega_rps: float


@dataclass(frozen=True)
class PoseRecord:
    """The robot's pose in the odometry frame (m, m, rad)."""

    t_ns: int
    x: float
    y: float
    theta: float


@dataclass(frozen=True)
class Mount:
    """Where the laser sits on the robot: offset (m) and yaw (rad) in the base frame.

    ``flipped`` is an upside-down scanner (rolled by π): its beams turn clockwise in the base frame.
    """

    x_m: float = 0.0
    y_m: float = 0.0
    yaw_rad: float = 0.0
    flipped: bool = False

    def describe(self) -> str:
        flip = ", upside down" if self.flipped else ""
        return f"x={self.x_m:+.3f} m, y={self.y_m:+.3f} m, yaw={math.degrees(self.yaw_rad):+.1f}°{flip}"


@dataclass(frozen=True)
class SourceInfo:
    """What an importer found in a log, before reading its messages.

    ``topics`` maps a role (``scan``, ``cmd``, ``odom``) to the topic or line type used;
    ``mount`` is None when the log does not say where the laser sits; robot limits are None
    when the log does not state them.
    """

    format: str
    topics: dict[str, str]
    mount: Mount | None = None
    mount_from: str = ""
    v_max_mps: float | None = None
    omega_max_rps: float | None = None
    teacher: str = "unknown"
    notes: tuple[str, ...] = ()


class Source(Protocol):
    """An opened robot log. The generators may be called more than once, in any order."""

    info: SourceInfo
    dropped: Counter[str]

    def iter_scans(self) -> Iterator[ScanRecord]: ...

    def iter_commands(self) -> Iterator[CommandRecord]: ...

    def iter_poses(self) -> Iterator[PoseRecord]: ...


@dataclass(frozen=True)
class TopicChoice:
    """Topics the user named (None: pick automatically)."""

    scan: str | None = None
    cmd: str | None = None
    odom: str | None = None


def no_return(ranges_m: np.ndarray, *, min_m: float = 0.0, max_m: float = math.inf) -> np.ndarray:
    """Ranges with every beam that has no return set to ``inf``.

    No return: inf, NaN, zero or negative, below the scanner's minimum, at or beyond its maximum.

    >>> no_return(np.array([1.0, 0.0, np.nan, 5.0, 0.01]), min_m=0.02, max_m=5.0).tolist()
    [1.0, inf, inf, inf, inf]
    """
    r = np.asarray(ranges_m, dtype=np.float64)
    bad = ~np.isfinite(r) | (r <= 0.0) | (r < min_m) | (r >= max_m)
    return np.where(bad, math.inf, r)


def stamp_ns(text: str) -> int:
    """A decimal seconds stamp (``"1134865053.682367"``, ``"1e-3"``) into int nanoseconds, exactly.

    >>> stamp_ns("1134865053.682367"), stamp_ns("0.5"), stamp_ns("12")
    (1134865053682367000, 500000000, 12000000000)
    """
    s = text.strip()
    if "e" in s.lower():  # rare; a float is exact enough for relative stamps written this way
        return round(float(s) * 1e9)
    neg = s.startswith("-")
    whole, _, frac = s.lstrip("+-").partition(".")
    ns = int(whole or "0") * 1_000_000_000 + int((frac + "000000000")[:9])
    return -ns if neg else ns
