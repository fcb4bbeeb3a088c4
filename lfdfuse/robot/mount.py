"""Where the laser sits on the robot, and its beams laid out in the robot's base frame.

A :class:`Mount` is planar: an offset and a yaw in the base frame, and whether the scanner is
upside down. :func:`mount_of` reads it from a base → laser transform; :func:`base_geometry`
turns a sensor-frame scan layout into the base frame (bearing 0 is the robot's forward), as
``import`` writes it and ``drive`` feeds it to the behaviours.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lfdfuse.errors import LfdError
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.robot.records import ScanRecord


class MountError(LfdError):
    """A laser mounting the behaviours cannot use (a scanner tilted out of the plane)."""


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


def mount_of(m: np.ndarray) -> Mount:
    """The planar mounting of a base→laser transform ``(4, 4)``; a scanner tilted out of the
    plane is a :class:`MountError`."""
    flipped = m[2, 2] < 0.0
    if abs(m[2, 2]) < 0.95:
        raise MountError("the laser is tilted out of the plane (its z axis is not vertical)")
    return Mount(float(m[0, 3]), float(m[1, 3]), math.atan2(m[1, 0], m[0, 0]), bool(flipped))


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def base_geometry(first: ScanRecord, mount: Mount) -> tuple[ScanGeometry, bool, bool]:
    """Base-frame geometry of the scans, whether to reverse the beams, and whether to drop the last.

    The last beam is dropped when it repeats the first one's bearing (a 361-beam 360° scan).
    """
    n, inc = first.count, first.increment_rad
    closing = n > 2 and abs(abs(inc) * (n - 1) - 2 * math.pi) < abs(inc) / 2
    n_out = n - 1 if closing else n
    if mount.flipped:  # bearing in the base frame = yaw − sensor angle: reverse to keep it increasing
        start = mount.yaw_rad - (first.start_rad + inc * (n_out - 1))
    else:
        start = mount.yaw_rad + first.start_rad
    return ScanGeometry(_wrap(start), inc, n_out, first.max_range_m), mount.flipped, closing
