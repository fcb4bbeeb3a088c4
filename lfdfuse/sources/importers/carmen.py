"""CARMEN logs (``.clf``, ``.log``, gzipped or not): ``FLASER``/``RLASER``/``ODOM``/``PARAM`` lines.

Line formats (old CARMEN, as in the Radish and SLAM benchmark logs)::

    FLASER n r_1 … r_n x y theta odom_x odom_y odom_theta ipc_timestamp host logger_timestamp
    ODOM x y theta tv rv accel ipc_timestamp host logger_timestamp
    PARAM name value [ipc_timestamp host logger_timestamp]

Beams start at −90° and step 1° for 180/181 readings, 0.5° for 360/361 (GMapping's reading of
these logs), else spread over 180°. A reading at or beyond the laser's maximum (``PARAM
robot_front_laser_max``, else 80 m; the logs write 81.83 or 81.91) is no return. Stamps are the
``ipc_timestamp`` (absolute or relative, kept as written); lines stamped 0 are dropped and the
rest sorted into time order. The robot's pose comes from the laser lines (every one carries it:
the corrected pose in corrected logs); ``ODOM`` lines give commands only when their ``tv``/``rv``
are not all zero, else commands are derived from the poses by the converter.
"""

from __future__ import annotations

import gzip
import math
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TypeVar

import numpy as np

from lfdfuse.robot.mount import Mount
from lfdfuse.robot.records import CommandRecord, PoseRecord, ScanRecord, no_return
from lfdfuse.sources.importers.records import SourceError, SourceInfo, TopicChoice, stamp_ns

NAME = "carmen"
_LASERS = ("FLASER", "RLASER")
_SIGNATURE = {"FLASER", "RLASER", "ODOM", "PARAM", "ROBOTLASER1", "RAWLASER1", "SYNC", "NEFF", "TRUEPOS"}
DEFAULT_MAX_RANGE_M = 80.0
T = TypeVar("T")


@dataclass(frozen=True, eq=False)
class _LaserLine:
    t_ns: int
    ranges_m: np.ndarray
    x: float
    y: float
    theta: float


def _open(path: Path) -> IO[str]:
    with path.open("rb") as f:
        gz = f.read(2) == b"\x1f\x8b"
    if gz:
        return gzip.open(path, "rt", encoding="latin-1")
    return path.open("r", encoding="latin-1")


def detect(path: Path) -> bool:
    """A (gzipped) text file whose first message lines are CARMEN messages."""
    if not path.is_file():
        return False
    seen = 0
    try:
        with _open(path) as f:
            for line in f:
                tok = line.split(maxsplit=1)
                if not tok or tok[0].startswith("#"):
                    continue
                if tok[0] not in _SIGNATURE:
                    return False
                seen += 1
                if seen >= 3:
                    break
    except (OSError, EOFError, UnicodeDecodeError, gzip.BadGzipFile):
        return False
    return seen > 0


def beam_geometry(n: int) -> tuple[float, float]:
    """``(start_rad, increment_rad)`` of an old-format CARMEN laser line with ``n`` readings."""
    if n in (180, 181):
        return -math.pi / 2, math.pi / 180
    if n in (360, 361):
        return -math.pi / 2, math.pi / 360
    return -math.pi / 2, (math.pi / (n - 1) if n > 1 else 0.0)


def _sorted(items: list[tuple[int, int, T]]) -> tuple[list[T], int]:
    """Items sorted by stamp (stable), and how many were out of time order."""
    late, latest = 0, -(2**63)
    for t, _, _ in items:
        late += t < latest
        latest = max(latest, t)
    return [it for _, _, it in sorted(items, key=lambda x: (x[0], x[1]))], late


class CarmenSource:
    """A CARMEN log parsed whole (it must be sorted): records are served from memory."""

    def __init__(self, path: Path, *, topics: TopicChoice) -> None:
        if topics.odom or topics.cmd:
            raise SourceError("a CARMEN log has no topics: --cmd/--odom do not apply")
        self.dropped: Counter[str] = Counter()
        lasers: dict[str, list[tuple[int, int, _LaserLine]]] = {k: [] for k in _LASERS}
        cmds: list[tuple[int, int, CommandRecord]] = []
        odom_lines = 0
        params: dict[str, str] = {}
        try:
            with _open(path) as f:
                for lineno, line in enumerate(f):
                    tok = line.split()
                    if not tok or tok[0].startswith("#"):
                        continue
                    try:
                        kind = tok[0]
                        if kind in _LASERS:
                            n = int(tok[1])
                            if len(tok) < n + 11:
                                self.dropped[f"{kind}: truncated line"] += 1
                                continue
                            t = stamp_ns(tok[n + 8])
                            if t == 0:
                                self.dropped[f"{kind}: time stamp 0"] += 1
                                continue
                            x, y, theta = map(float, tok[n + 2 : n + 5])
                            ranges = np.array(tok[2 : 2 + n], dtype=np.float64)
                            lasers[kind].append((t, lineno, _LaserLine(t, ranges, x, y, theta)))
                        elif kind == "ODOM":
                            t = stamp_ns(tok[7])
                            if t == 0:
                                self.dropped["ODOM: time stamp 0"] += 1
                                continue
                            odom_lines += 1
                            cmds.append((t, lineno, CommandRecord(t, float(tok[4]), float(tok[5]))))
                        elif kind == "PARAM":
                            params[tok[1]] = tok[2]
                        else:
                            self.dropped[f"{kind}: not a laser, odometry or parameter line"] += 1
                    except (ValueError, IndexError):
                        self.dropped[f"{tok[0]}: unparsable line"] += 1
        except (OSError, EOFError, UnicodeDecodeError, gzip.BadGzipFile) as exc:
            raise SourceError(f"{path}: cannot read the CARMEN log ({exc})") from exc

        kind = "FLASER" if lasers["FLASER"] or not lasers["RLASER"] else "RLASER"
        other = "RLASER" if kind == "FLASER" else "FLASER"
        if lasers[other]:
            self.dropped[f"{other}: one laser is imported ({kind})"] += len(lasers[other])
        if not lasers[kind]:
            raise SourceError(f"{path}: the CARMEN log has no FLASER or RLASER lines")
        notes: list[str] = []
        laser_lines, late = _sorted(lasers[kind])
        if late:
            notes.append(f"{late} {kind} lines out of time order (sorted)")
        prefix = "robot_frontlaser" if kind == "FLASER" else "robot_rearlaser"
        max_key = "robot_front_laser_max" if kind == "FLASER" else "robot_rear_laser_max"
        self._max_m = _param(params, max_key, DEFAULT_MAX_RANGE_M)
        self._laser = laser_lines
        cmd_list, late = _sorted(cmds)
        moving = any(c.v_mps != 0.0 or c.omega_rps != 0.0 for c in cmd_list)
        self._cmds = cmd_list if moving else []
        if odom_lines and not moving:
            self.dropped["ODOM: tv and rv all zero (the pose comes from the laser lines)"] += odom_lines
        elif late:
            notes.append(f"{late} ODOM lines out of time order (sorted)")
        yaw = _param(params, f"{prefix}_angular_offset", 0.0) + (math.pi if kind == "RLASER" else 0.0)
        mount = Mount(
            _param(params, f"{prefix}_offset", 0.0), _param(params, f"{prefix}_side_offset", 0.0), yaw
        )
        self.info = SourceInfo(
            format=NAME,
            topics={"scan": kind, "odom": f"{kind} pose", **({"cmd": "ODOM tv/rv"} if self._cmds else {})},
            mount=mount,
            mount_from=f"PARAM {prefix}_offset" if f"{prefix}_offset" in params else "CARMEN default",
            v_max_mps=_param(params, "robot_max_t_vel", None),
            omega_max_rps=_param(params, "robot_max_r_vel", None),
            notes=tuple(notes),
        )

    def iter_scans(self) -> Iterator[ScanRecord]:
        for ln in self._laser:
            start, inc = beam_geometry(len(ln.ranges_m))
            yield ScanRecord(ln.t_ns, start, inc, no_return(ln.ranges_m, max_m=self._max_m), self._max_m)

    def iter_commands(self) -> Iterator[CommandRecord]:
        yield from self._cmds

    def iter_poses(self) -> Iterator[PoseRecord]:
        for ln in self._laser:
            yield PoseRecord(ln.t_ns, ln.x, ln.y, ln.theta)


def _param(params: dict[str, str], key: str, default: T) -> float | T:
    try:
        return float(params[key]) if key in params else default
    except ValueError as exc:
        raise SourceError(f"PARAM {key} is not a number: {params[key]!r}") from exc


def open_source(path: Path, *, topics: TopicChoice) -> CarmenSource:
    return CarmenSource(path, topics=topics)
