"""A run loaded into arrays: the ``/scan``, ``/sonar``, ``/pose``, ``/cmd_vel`` and ``/targets``
messages of a log, decoded one at a time by a :class:`RunBuilder`.

No file access here: :func:`lfdfuse.log.reader.read_run` feeds a builder from one pass over a
file, and a reader of several kinds (:func:`lfdfuse.segment.read.read_segmented_and_run`) feeds
it from its own pass.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import orjson

from lfdfuse.errors import LogError
from lfdfuse.log.sensing import (
    ScanMessage,
    decode_detections,
    decode_pose,
    decode_scan,
    decode_twist,
    scan_geometry,
)
from lfdfuse.log.stamps import check_log_time
from lfdfuse.robot.readings import Detection, ScanGeometry

#: most beams a scan may have (real 2D lidars have up to a few thousand)
MAX_BEAMS = 8192
#: the topics a :class:`Run` is read from
RUN_TOPICS = ("/scan", "/sonar", "/pose", "/cmd_vel", "/targets")


@dataclass(frozen=True)
class Run:
    """A run loaded into arrays, on the clock of its laser scans.

    ``t_ns (N,)``, ``ranges_m (N, B)``; ``sonar_m (N, S)`` and ``pose (N, 3)`` (x, y, yaw) are
    held to each scan time (None when the log lacks them); commands keep their own clock
    ``cmd_t_ns (M,)``, ``cmd_v_mps (M,)``, ``cmd_omega_rps (M,)``.
    """

    t_ns: np.ndarray
    geometry: ScanGeometry
    ranges_m: np.ndarray
    cmd_t_ns: np.ndarray
    cmd_v_mps: np.ndarray
    cmd_omega_rps: np.ndarray
    sonar_m: np.ndarray | None = None
    sonar_geometry: ScanGeometry | None = None
    pose: np.ndarray | None = None
    detections: list[tuple[Detection, ...]] = field(default_factory=list)
    metadata: dict[str, str] = field(default_factory=dict)
    world_yaml: str | None = None
    topics: tuple[str, ...] = ()

    def __len__(self) -> int:
        return len(self.t_ns)


def hold(src_t: np.ndarray, dst_t: np.ndarray) -> np.ndarray:
    """Index of the latest ``src_t`` at or before each ``dst_t`` (0 before the first)."""
    return np.clip(np.searchsorted(src_t, dst_t, side="right") - 1, 0, max(len(src_t) - 1, 0))


class _Rows:
    """A growing ``(n, width)`` float64 array: one row per scan, never a Python list per beam."""

    def __init__(self, width: int, capacity: int) -> None:
        self.data = np.empty((max(capacity, 16), width), dtype=np.float64)
        self.n = 0

    def append(self, row: np.ndarray) -> None:
        if self.n == len(self.data):
            grown = np.empty((2 * len(self.data), self.data.shape[1]), dtype=np.float64)
            grown[: self.n] = self.data
            self.data = grown
        self.data[self.n] = row
        self.n += 1

    def array(self) -> np.ndarray:
        return self.data[: self.n] if self.n == len(self.data) else self.data[: self.n].copy()


def meta_float(meta: dict[str, str], key: str, default: float, *, path: str | Path | None = None) -> float:
    """A positive number from provenance metadata; the default when absent.

    Present but not a positive number (``"far"``, ``"nan"``, ``"-1"``) is a :class:`LogError`: the
    value sets which ranges count as no return, so a guess would change what is learned.
    """
    if key not in meta:
        return default
    text = meta[key]
    try:
        value = float(text)
    except (TypeError, ValueError):
        value = math.nan
    if not value > 0:  # also NaN
        where = f"{path}: " if path is not None else "the log's "
        raise LogError(f"{where}metadata {key} must be a positive number, got {text[:40]!r}")
    return value


_DECODE_ERRORS = (orjson.JSONDecodeError, KeyError, TypeError, ValueError, IndexError, AttributeError)


def _json(path: str | Path, topic: str, t_ns: int, data: bytes) -> dict[str, Any]:
    try:
        msg = orjson.loads(data)
    except orjson.JSONDecodeError as exc:
        raise LogError(f"{path}: a {topic} message at t={t_ns} ns is not valid JSON ({exc})") from exc
    if not isinstance(msg, dict):
        raise LogError(f"{path}: a {topic} message at t={t_ns} ns is not a JSON object")
    return msg


def _ranges(path: str | Path, topic: str, t_ns: int, scan: ScanMessage) -> np.ndarray:
    values = scan.ranges_m
    if not isinstance(values, list) or not values:
        raise LogError(f"{path}: a {topic} message at t={t_ns} ns has no beams")
    if len(values) > MAX_BEAMS:
        raise LogError(
            f"{path}: a {topic} message has {len(values)} beams; at most {MAX_BEAMS} are supported"
        )
    if not (math.isfinite(scan.start_rad) and math.isfinite(scan.end_rad)):
        raise LogError(f"{path}: a {topic} message at t={t_ns} ns has non-finite start or end angles")
    try:
        row = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise LogError(f"{path}: a {topic} message at t={t_ns} ns has ranges that are not numbers") from exc
    if row.ndim != 1:
        raise LogError(f"{path}: a {topic} message at t={t_ns} ns has ranges that are not numbers")
    return row


def _detections(path: str | Path, t_ns: int, msg: dict[str, Any]) -> tuple[Detection, ...]:
    dets = decode_detections(msg)
    for d in dets:
        if (
            not isinstance(d.name, str)
            or not d.name
            or len(d.name) > 64
            or not d.name.replace("_", "").isalnum()
        ):
            raise LogError(f"{path}: a /targets message at t={t_ns} ns names an invalid target")
        if not (math.isfinite(float(d.bearing_rad)) and math.isfinite(float(d.range_m))):
            raise LogError(f"{path}: a /targets message at t={t_ns} ns has a non-finite bearing or range")
    return tuple(Detection(d.name, float(d.bearing_rad), float(d.range_m)) for d in dets)


class RunBuilder:
    """A :class:`Run` built one message at a time: ``feed`` each message of :data:`RUN_TOPICS` in
    log-time order, then ``finish``.

    ``channels`` is the file's summary (topic → schema name, message encoding, count: the
    counts size the arrays), ``metadata`` its provenance. Memory is the arrays themselves (scans
    are decoded one message at a time into a preallocated ``(N, B)`` array); every malformed
    message is a :class:`LogError` naming it.
    """

    def __init__(
        self, path: str | Path, *, channels: Mapping[str, tuple[str, str, int]], metadata: dict[str, str]
    ) -> None:
        for topic in ("/scan", "/cmd_vel"):
            got = channels.get(topic)
            if got is not None and got[1] != "json":
                raise LogError(
                    f"{path}: {topic} is {got[1] or 'unknown'}-encoded {got[0] or 'data'}, not an lfdfuse log:"
                    f" run `lfdfuse import {path}` first"
                )
        self.path = path
        self.metadata = metadata
        self.counts = {topic: n for topic, (_s, _e, n) in channels.items()}
        self.scans: _Rows | None = None
        self.scan_t: list[int] = []
        self.sonars: _Rows | None = None
        self.sonar_t: list[int] = []
        self.pose_t: list[int] = []
        self.poses: list[tuple[float, float, float]] = []
        self.cmd_t: list[int] = []
        self.cmds: list[tuple[float, float]] = []
        self.dets: list[tuple[int, tuple[Detection, ...]]] = []
        self.first_scan: ScanMessage | None = None
        self.first_sonar: ScanMessage | None = None
        self.topics: set[str] = set()

    def feed(self, topic: str, encoding: str, t_ns: int, data: bytes) -> None:
        """One message (its log time is checked here: a caller's iterator need not)."""
        # times stay int64 nanoseconds: a float64 cannot hold an epoch stamp to the nanosecond, and
        # pairing commands with scans by rounded times pairs the wrong ones
        path = self.path
        check_log_time(path, topic, t_ns)
        if encoding != "json":
            raise LogError(
                f"{path}: {topic} is {encoding or 'unknown'}-encoded: run `lfdfuse import {path}` first"
            )
        self.topics.add(topic)
        msg = _json(path, topic, t_ns, data)
        try:
            if topic == "/scan":
                scan = decode_scan(msg)
                row = _ranges(path, topic, t_ns, scan)
                if self.scans is None:
                    self.first_scan, self.scans = scan, _Rows(len(row), self.counts.get(topic, 0))
                elif len(row) != self.scans.data.shape[1]:
                    raise LogError(
                        f"{path}: /scan messages have different beam counts ({self.scans.data.shape[1]} and {len(row)})"
                    )
                self.scans.append(row)
                self.scan_t.append(t_ns)
            elif topic == "/sonar":
                sonar = decode_scan(msg)
                row = _ranges(path, topic, t_ns, sonar)
                if self.sonars is None:
                    self.first_sonar, self.sonars = sonar, _Rows(len(row), self.counts.get(topic, 0))
                elif len(row) != self.sonars.data.shape[1]:
                    raise LogError(f"{path}: /sonar messages have different beam counts")
                self.sonars.append(row)
                self.sonar_t.append(t_ns)
            elif topic == "/pose":
                self.pose_t.append(t_ns)
                self.poses.append(decode_pose(msg))
            elif topic == "/cmd_vel":
                self.cmd_t.append(t_ns)
                self.cmds.append(decode_twist(msg))
            elif topic == "/targets":
                self.dets.append((t_ns, _detections(path, t_ns, msg)))
        except _DECODE_ERRORS as exc:
            raise LogError(
                f"{path}: a {topic} message at t={t_ns} ns is malformed ({exc.__class__.__name__}: {exc})"
            ) from exc

    def finish(self) -> Run:
        """The run (without its world file: the file's attachments are the reader's)."""
        path = self.path
        missing = [t for t in ("/scan", "/cmd_vel") if t not in self.topics]
        if missing:
            raise LogError(f"{path}: the log has no {' and no '.join(missing)} messages")
        assert self.first_scan is not None and self.scans is not None
        t = np.array(self.scan_t, dtype=np.int64)
        ranges = self.scans.array()
        self.scans = None
        meta = self.metadata
        # without our metadata the max range is unknown: then no range counts as a sentinel (inf), which
        # is harmless to the primitives, which only look at returns nearer than d_max
        max_range = meta_float(meta, "laser_max_range_m", math.inf, path=path)
        geom = scan_geometry(self.first_scan, ranges.shape[1], max_range)
        cmd = np.array(self.cmds, dtype=np.float64).reshape(-1, 2)
        run_kwargs: dict[str, Any] = {}
        if self.sonars is not None and self.first_sonar is not None:
            st = np.array(self.sonar_t, dtype=np.int64)
            sr = self.sonars.array()
            run_kwargs["sonar_m"] = sr[hold(st, t)]
            run_kwargs["sonar_geometry"] = scan_geometry(
                self.first_sonar, sr.shape[1], meta_float(meta, "sonar_max_range_m", math.inf, path=path)
            )
        if self.poses:
            pa = np.array(self.poses, dtype=np.float64)
            run_kwargs["pose"] = pa[hold(np.array(self.pose_t, dtype=np.int64), t)]
        dets = self.dets
        if dets:
            dt = np.array([d[0] for d in dets], dtype=np.int64)
            idx = hold(dt, t)
            run_kwargs["detections"] = [
                dets[i][1] if dets[i][0] <= tt else () for i, tt in zip(idx, t, strict=True)
            ]
        else:
            run_kwargs["detections"] = [() for _ in t]
        return Run(
            t_ns=t,
            geometry=geom,
            ranges_m=ranges,
            cmd_t_ns=np.array(self.cmd_t, dtype=np.int64),
            cmd_v_mps=cmd[:, 0],
            cmd_omega_rps=cmd[:, 1],
            metadata=meta,
            topics=tuple(sorted(self.topics)),
            **run_kwargs,
        )


__all__ = ["MAX_BEAMS", "RUN_TOPICS", "Run", "RunBuilder", "hold", "meta_float"]
