"""The MCAP reader: messages as a generator, and a whole run loaded into arrays."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import orjson
from mcap.exceptions import McapError
from mcap.reader import make_reader

from lfdfuse.errors import LogError
from lfdfuse.log.messages import PROVENANCE, RawMessage, from_stamp
from lfdfuse.log.sensing import (
    ScanMessage,
    decode_detections,
    decode_pose,
    decode_scan,
    decode_twist,
    scan_geometry,
)
from lfdfuse.sim.sensors import Detection, ScanGeometry


def _open(path: str | Path) -> Any:
    p = Path(path)
    if not p.is_file():
        raise LogError(f"no such file: {p}")
    try:
        stream = p.open("rb")
    except OSError as exc:
        raise LogError(f"cannot read {p}: {exc.strerror}") from exc
    return stream


def iter_messages(
    path: str | Path, *, topics: list[str] | None = None
) -> Iterator[tuple[str, str, int, bytes]]:
    """Yield ``(topic, schema_name, log_time_ns, data)`` in log-time order."""
    with _open(path) as stream:
        try:
            reader = make_reader(stream)
            for schema, channel, message in reader.iter_messages(topics=topics, log_time_order=True):
                yield channel.topic, (schema.name if schema else ""), message.log_time, message.data
        except (McapError, ValueError, EOFError, OSError, KeyError, AssertionError) as exc:
            raise LogError(f"{path}: not a readable MCAP file ({exc.__class__.__name__}: {exc})") from exc


def iter_raw(path: str | Path, *, exclude_prefix: str | None = None) -> Iterator[RawMessage]:
    """Every message of a file in log-time order, optionally without topics under a prefix."""
    with _open(path) as stream:
        try:
            reader = make_reader(stream)
            for schema, channel, message in reader.iter_messages(log_time_order=True):
                if exclude_prefix is not None and channel.topic.startswith(exclude_prefix):
                    continue
                yield RawMessage(
                    channel.topic,
                    schema.name if schema else "",
                    schema.encoding if schema else "",
                    schema.data if schema else b"",
                    channel.message_encoding,
                    message.log_time,
                    message.publish_time,
                    message.data,
                )
        except (McapError, ValueError, EOFError, OSError, KeyError, AssertionError) as exc:
            raise LogError(f"{path}: not a readable MCAP file ({exc.__class__.__name__}: {exc})") from exc


def iter_attachments(path: str | Path) -> Iterator[tuple[str, str, bytes]]:
    """``(name, media_type, data)`` of every attachment."""
    with _open(path) as stream:
        try:
            for att in make_reader(stream).iter_attachments():
                yield att.name, att.media_type, att.data
        except (McapError, ValueError, EOFError, OSError) as exc:
            raise LogError(f"{path}: not a readable MCAP file ({exc})") from exc


@dataclass(frozen=True)
class FileInfo:
    """What ``lfdfuse inspect`` shows of any MCAP file."""

    channels: dict[str, tuple[str, str, int]]  # topic → (schema name, message encoding, count)
    start_ns: int
    end_ns: int
    metadata: dict[str, dict[str, str]]
    attachments: list[str]
    library: str


def file_info(path: str | Path) -> FileInfo:
    with _open(path) as stream:
        try:
            reader = make_reader(stream)
            header = reader.get_header()
            summary = reader.get_summary()
            counts: dict[int, int] = {}
            start = end = 0
            if summary is not None and summary.statistics is not None:
                counts = dict(summary.statistics.channel_message_counts)
                start, end = summary.statistics.message_start_time, summary.statistics.message_end_time
            channels: dict[str, tuple[str, str, int]] = {}
            if summary is not None:
                for cid, ch in sorted(summary.channels.items()):
                    sch = summary.schemas.get(ch.schema_id)
                    channels[ch.topic] = (sch.name if sch else "", ch.message_encoding, counts.get(cid, 0))
            metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
            attachments = [a.name for a in reader.iter_attachments()]
        except (McapError, ValueError, EOFError, OSError, KeyError, AssertionError) as exc:
            raise LogError(f"{path}: not a readable MCAP file ({exc.__class__.__name__}: {exc})") from exc
    return FileInfo(channels, start, end, metadata, attachments, header.library)


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


def _ranges_array(rows: list[list[float]]) -> np.ndarray:
    return np.array(rows, dtype=np.float64)


def read_run(path: str | Path) -> Run:
    """Load an lfdfuse log (simulated, executed or imported) into arrays."""
    scans: list[tuple[int, list[float]]] = []
    sonars: list[tuple[int, list[float]]] = []
    pose_t: list[int] = []
    poses: list[tuple[float, float, float]] = []
    cmd_t: list[int] = []
    cmds: list[tuple[float, float]] = []
    dets: list[tuple[int, tuple[Detection, ...]]] = []
    first_scan: ScanMessage | None = None
    first_sonar: ScanMessage | None = None
    topics: set[str] = set()
    # times stay int64 nanoseconds: a float64 cannot hold an epoch stamp to the nanosecond, and
    # pairing commands with scans by rounded times pairs the wrong ones
    for topic, _schema, t_ns, data in iter_messages(
        path, topics=["/scan", "/sonar", "/pose", "/cmd_vel", "/targets"]
    ):
        topics.add(topic)
        msg = orjson.loads(data)
        if topic == "/scan":
            scan = decode_scan(msg)
            first_scan = first_scan or scan
            scans.append((t_ns, scan.ranges_m))
        elif topic == "/sonar":
            sonar = decode_scan(msg)
            first_sonar = first_sonar or sonar
            sonars.append((t_ns, sonar.ranges_m))
        elif topic == "/pose":
            pose_t.append(t_ns)
            poses.append(decode_pose(msg))
        elif topic == "/cmd_vel":
            cmd_t.append(t_ns)
            cmds.append(decode_twist(msg))
        elif topic == "/targets":
            dets.append((t_ns, decode_detections(msg)))
    missing = [t for t in ("/scan", "/cmd_vel") if t not in topics]
    if missing:
        raise LogError(f"{path}: the log has no {' and no '.join(missing)} messages")
    assert first_scan is not None
    counts = {len(r) for _, r in scans}
    if len(counts) != 1:
        raise LogError(f"{path}: /scan messages have different beam counts {sorted(counts)}")
    t = np.array([s[0] for s in scans], dtype=np.int64)
    ranges = _ranges_array([s[1] for s in scans])
    meta: dict[str, str] = file_info(path).metadata.get(PROVENANCE, {})
    # without our metadata the max range is unknown: then no range counts as a sentinel (inf), which
    # is harmless to the primitives, which only look at returns nearer than d_max
    max_range = float(meta.get("laser_max_range_m", math.inf))
    geom = scan_geometry(first_scan, ranges.shape[1], max_range)
    cmd = np.array(cmds, dtype=np.float64).reshape(-1, 2)
    run_kwargs: dict[str, Any] = {}
    if sonars and first_sonar is not None:
        st = np.array([s[0] for s in sonars], dtype=np.int64)
        sr = _ranges_array([s[1] for s in sonars])
        run_kwargs["sonar_m"] = sr[hold(st, t)]
        run_kwargs["sonar_geometry"] = scan_geometry(
            first_sonar, sr.shape[1], float(meta.get("sonar_max_range_m", math.inf))
        )
    if poses:
        pa = np.array(poses, dtype=np.float64)
        run_kwargs["pose"] = pa[hold(np.array(pose_t, dtype=np.int64), t)]
    if dets:
        dt = np.array([d[0] for d in dets], dtype=np.int64)
        idx = hold(dt, t)
        run_kwargs["detections"] = [
            dets[i][1] if dets[i][0] <= tt else () for i, tt in zip(idx, t, strict=True)
        ]
    else:
        run_kwargs["detections"] = [() for _ in t]
    world_yaml = None
    for name, _media, data in iter_attachments(path):
        if name == "world.yaml":
            world_yaml = data.decode()
    return Run(
        t_ns=t,
        geometry=geom,
        ranges_m=ranges,
        cmd_t_ns=np.array(cmd_t, dtype=np.int64),
        cmd_v_mps=cmd[:, 0],
        cmd_omega_rps=cmd[:, 1],
        metadata=meta,
        world_yaml=world_yaml,
        topics=tuple(sorted(topics)),
        **run_kwargs,
    )


__all__ = [
    "FileInfo",
    "RawMessage",
    "Run",
    "file_info",
    "from_stamp",
    "hold",
    "iter_attachments",
    "iter_messages",
    "iter_raw",
    "read_run",
]
