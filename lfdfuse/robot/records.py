"""Time-stamped records in the sensor's own frame, as a log or a wire carries them.

An importer reads them from a robot log, ``drive`` decodes them off the wire: a
:class:`ScanRecord` (a planar laser scan, every beam without a return set to ``inf``), a
:class:`CommandRecord` (a velocity command) and a :class:`PoseRecord` (odometry). Stamps are
int64 nanoseconds (epoch stamps stay exact).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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


def same_geometry(a: ScanRecord, b: ScanRecord) -> bool:
    """Whether two scans share one beam layout (count, start, increment, max range).

    A scanner keeps its layout; a scan that differs from the first is another sensor's, or noise.
    """
    return (
        a.count == b.count
        and abs(a.start_rad - b.start_rad) < 1e-6
        and abs(a.increment_rad - b.increment_rad) < 1e-9
        and a.max_range_m == b.max_range_m
    )


def no_return(ranges_m: np.ndarray, *, min_m: float = 0.0, max_m: float = math.inf) -> np.ndarray:
    """Ranges with every beam that has no return set to ``inf``.

    No return: inf, NaN, zero or negative, below the scanner's minimum, at or beyond its maximum.

    >>> no_return(np.array([1.0, 0.0, np.nan, 5.0, 0.01]), min_m=0.02, max_m=5.0).tolist()
    [1.0, inf, inf, inf, inf]
    """
    r = np.asarray(ranges_m, dtype=np.float64)
    bad = ~np.isfinite(r) | (r <= 0.0) | (r < min_m) | (r >= max_m)
    return np.where(bad, math.inf, r)
