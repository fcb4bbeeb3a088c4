"""BreezySLAM / CoreSLAM ``.dat`` logs (the Mines ParisTech rover with a Hokuyo URG-04LX).

One line per scan, whitespace-separated integers: column 0 the time stamp in µs, columns 2 and 3
the cumulative left and right wheel ticks, columns 24… the ranges in mm (0 = no return); the last
token is not a range. The scanner's beams spread counter-clockwise over 240° from −120°
(CoreSLAM's ``-detection_angle/2 + i·detection_angle/(size-1)``), 0.145 m ahead of the axle.
Poses are integrated from the wheel ticks (differential drive); commands are derived from them by
the converter. Rover defaults (BreezySLAM's ``examples/mines.py``): wheel radius 77 mm, half axle
165 mm, 2000 ticks per wheel revolution.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lfdfuse.robot.mount import Mount
from lfdfuse.robot.records import CommandRecord, PoseRecord, ScanRecord, no_return
from lfdfuse.sources.importers.records import SourceError, SourceInfo, TopicChoice

NAME = "breezyslam"
FIRST_RANGE = 24


@dataclass(frozen=True)
class Rover:
    """The scanner and wheel odometry of a BreezySLAM log (defaults: the Mines rover)."""

    fov_rad: float = math.radians(240.0)
    max_range_m: float = 5.6  # URG-04LX: 5.6 m (the logs hold up to 5580 mm)
    laser_offset_m: float = 0.145
    wheel_radius_m: float = 0.077
    half_axle_m: float = 0.165
    ticks_per_rev: int = 2000


def _rows(path: Path) -> Iterator[tuple[int, list[str]]]:
    with path.open("r", encoding="latin-1") as f:
        for lineno, line in enumerate(f):
            tok = line.split()
            if tok:
                yield lineno, tok


def detect(path: Path) -> bool:
    """A text file of long all-number lines: an integer µs stamp, odometry, ranges in mm."""
    if not path.is_file():
        return False
    try:
        for _, tok in _rows(path):
            if len(tok) <= FIRST_RANGE + 10 or not tok[0].isdigit():
                return False
            np.array(tok, dtype=np.float64)
            return all(t.isdigit() for t in tok[FIRST_RANGE:-1])
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    return False


class BreezySource:
    """A ``.dat`` log parsed whole (see the module docstring)."""

    def __init__(self, path: Path, *, topics: TopicChoice, rover: Rover = Rover()) -> None:
        if topics.scan or topics.cmd or topics.odom:
            raise SourceError("a BreezySLAM log has no topics: --scan/--cmd/--odom do not apply")
        self.rover = rover
        self.dropped: Counter[str] = Counter()
        rows: list[tuple[int, int, int, np.ndarray]] = []
        width = 0
        try:
            for lineno, tok in _rows(path):
                try:
                    ranges = np.array(tok[FIRST_RANGE:-1], dtype=np.float64) / 1000.0
                    row = (int(tok[0]) * 1000, int(tok[2]), int(tok[3]), ranges)
                except (ValueError, IndexError):
                    self.dropped[f"line {lineno + 1}: unparsable"] += 1
                    continue
                width = width or len(ranges)
                if len(ranges) != width or width == 0:
                    self.dropped["scan: beam count differs from the first line"] += 1
                    continue
                rows.append(row)
        except (OSError, UnicodeDecodeError) as exc:
            raise SourceError(f"{path}: cannot read the BreezySLAM log ({exc})") from exc
        if not rows:
            raise SourceError(f"{path}: no scan lines")
        late = sum(b[0] < a[0] for a, b in zip(rows, rows[1:], strict=False))
        self._rows = sorted(rows, key=lambda r: r[0])
        self.info = SourceInfo(
            format=NAME,
            topics={"scan": "ranges (columns 24…)", "odom": "wheel ticks (columns 2, 3)"},
            mount=Mount(rover.laser_offset_m, 0.0, 0.0),
            mount_from="BreezySLAM rover (URG-04LX 0.145 m ahead)",
            notes=(f"{late} lines out of time order (sorted)",) if late else (),
        )

    def iter_scans(self) -> Iterator[ScanRecord]:
        ro = self.rover
        for t_ns, _, _, ranges in self._rows:
            inc = ro.fov_rad / (len(ranges) - 1) if len(ranges) > 1 else 0.0
            yield ScanRecord(
                t_ns, -ro.fov_rad / 2, inc, no_return(ranges, max_m=ro.max_range_m), ro.max_range_m
            )

    def iter_commands(self) -> Iterator[CommandRecord]:
        return iter(())

    def iter_poses(self) -> Iterator[PoseRecord]:
        """Differential-drive dead reckoning from the cumulative wheel ticks, starting at the origin."""
        ro = self.rover
        per_tick = 2 * math.pi * ro.wheel_radius_m / ro.ticks_per_rev
        x = y = theta = 0.0
        prev: tuple[int, int] | None = None
        for t_ns, left, right, _ in self._rows:
            if prev is not None:
                dl, dr = (left - prev[0]) * per_tick, (right - prev[1]) * per_tick
                ds, dth = (dl + dr) / 2, (dr - dl) / (2 * ro.half_axle_m)
                x += ds * math.cos(theta + dth / 2)
                y += ds * math.sin(theta + dth / 2)
                theta = math.atan2(math.sin(theta + dth), math.cos(theta + dth))
            prev = (left, right)
            yield PoseRecord(t_ns, x, y, theta)


def open_source(path: Path, *, topics: TopicChoice) -> BreezySource:
    return BreezySource(path, topics=topics)
