"""The MCAP reader: messages as a generator, and a whole run loaded into arrays."""

from __future__ import annotations

import io
import math
import os
import stat
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import orjson
import zstandard
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
from lfdfuse.log.stamps import (
    MAX_T_NS,  # latest log time we read: int64 ns in our arrays (MCAP allows uint64)
)
from lfdfuse.sim.sensors import Detection, ScanGeometry

#: the first bytes of every MCAP file
MCAP_MAGIC = b"\x89MCAP0\r\n"
#: most beams a scan may have (real 2D lidars have up to a few thousand)
MAX_BEAMS = 8192
#: largest world attachment we read back (the world file a simulated demo carries)
MAX_WORLD_BYTES = 16 * 2**20
#: what the mcap library and its decompressors raise on a damaged file
_READ_ERRORS = (
    McapError,
    ValueError,
    EOFError,
    OSError,
    KeyError,
    IndexError,
    TypeError,
    AssertionError,
    OverflowError,
    RuntimeError,  # lz4
    MemoryError,  # a size the walk of _check_chunks did not reach (past damaged framing)
    struct.error,
    zstandard.ZstdError,
)
_IMPORT_SUFFIXES = (".bag", ".db3", ".clf", ".log", ".gz", ".dat")


class _Bounded(io.BufferedReader):
    """A file whose reads never ask for more than what is left of it.

    MCAP records carry their own lengths; a damaged or hostile one claims exabytes, and a plain
    ``read(n)`` allocates ``n`` bytes before it finds the file shorter. Clamped, the read comes
    back short and the mcap library reports a truncated record instead.
    """

    def __init__(self, raw: io.FileIO) -> None:
        super().__init__(raw)
        self._size = os.fstat(raw.fileno()).st_size

    def read(self, size: int | None = -1, /) -> bytes:
        if size is not None and size >= 0:
            size = max(0, min(size, self._size - self.tell()))
        return super().read(size)


def check_log_file(path: str | Path) -> Path:
    """``path`` as a :class:`Path` if it is an existing regular file; else a one-line :class:`LogError`.

    Checked before anything opens the file: a FIFO or a device would block or never end.
    """
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise LogError(f"no such file: {p}") from None
    except OSError as exc:
        raise LogError(f"cannot read {p}: {exc.strerror}") from exc
    if stat.S_ISDIR(st.st_mode):
        raise LogError(
            f"{p} is a folder, not an MCAP file (a rosbag2 folder? run `lfdfuse import {p}` first)"
        )
    if not stat.S_ISREG(st.st_mode):
        raise LogError(f"{p} is not a regular file")
    return p


#: largest chunk we decompress (writers use ~1-4 MB; the size is allocated before decompressing)
MAX_CHUNK_BYTES = 2**30
_CHUNK, _DATA_END, _FOOTER = 0x06, 0x0F, 0x02


def _check_chunks(p: Path, stream: _Bounded) -> None:
    """Refuse a chunk whose declared uncompressed size is absurd, before the mcap library allocates
    it: a record walk over the data section (one small read per record), stopping where the framing
    breaks (the library reports that itself)."""
    size, pos = stream._size, len(MCAP_MAGIC)
    while pos + 9 <= size:
        stream.seek(pos)
        head = stream.read(9 + 24)
        if len(head) < 9:
            break
        opcode, length = struct.unpack_from("<BQ", head)
        if opcode in (_DATA_END, _FOOTER):
            break
        if opcode == _CHUNK and len(head) == 33:
            (uncompressed,) = struct.unpack_from("<Q", head, 9 + 16)
            if uncompressed > MAX_CHUNK_BYTES:
                raise LogError(
                    f"{p}: not a readable MCAP file (a chunk at byte {pos} claims {uncompressed} bytes"
                    f" uncompressed; at most {MAX_CHUNK_BYTES // 2**20} MB are read)"
                )
        pos += 9 + length
    stream.seek(0)


def _open(path: str | Path) -> Any:
    p = check_log_file(path)
    try:
        stream = _Bounded(io.FileIO(p, "rb"))
    except OSError as exc:
        raise LogError(f"cannot read {p}: {exc.strerror}") from exc
    if stream.read(8) != MCAP_MAGIC:
        stream.close()
        hint = (
            f"; run `lfdfuse import {p}` first"
            if p.suffix in _IMPORT_SUFFIXES
            else "; other robot logs go through `lfdfuse import`"
        )
        raise LogError(f"{p}: not a readable MCAP file (it does not start like one){hint}")
    try:
        _check_chunks(p, stream)
    except BaseException:
        stream.close()
        raise
    return stream


def _unreadable(path: str | Path, exc: BaseException) -> LogError:
    text = str(exc).splitlines()[0][:120] if str(exc) else exc.__class__.__name__
    return LogError(f"{path}: not a readable MCAP file (damaged: {text})")


def _time(path: str | Path, topic: str, t_ns: int) -> int:
    if t_ns > MAX_T_NS:
        raise LogError(
            f"{path}: a {topic} message has log time {t_ns} ns, past the int64 nanoseconds lfdfuse reads"
        )
    return t_ns


def _iter(path: str | Path, topics: list[str] | None) -> Iterator[tuple[str, str, str, int, bytes]]:
    """``(topic, schema name, message encoding, log time ns, data)`` in log-time order."""
    with _open(path) as stream:
        try:
            reader = make_reader(stream)
            for schema, channel, message in reader.iter_messages(topics=topics, log_time_order=True):
                _time(path, channel.topic, message.log_time)
                yield (
                    channel.topic,
                    schema.name if schema else "",
                    channel.message_encoding,
                    message.log_time,
                    message.data,
                )
        except _READ_ERRORS as exc:
            raise _unreadable(path, exc) from exc


def iter_messages(
    path: str | Path, *, topics: list[str] | None = None
) -> Iterator[tuple[str, str, int, bytes]]:
    """Yield ``(topic, schema_name, log_time_ns, data)`` in log-time order."""
    for topic, schema, _enc, t, data in _iter(path, topics):
        yield topic, schema, t, data


def iter_raw(path: str | Path, *, exclude_prefix: str | None = None) -> Iterator[RawMessage]:
    """Every message of a file in log-time order, optionally without topics under a prefix."""
    with _open(path) as stream:
        try:
            reader = make_reader(stream)
            for schema, channel, message in reader.iter_messages(log_time_order=True):
                if exclude_prefix is not None and channel.topic.startswith(exclude_prefix):
                    continue
                _time(path, channel.topic, message.log_time)
                _time(path, channel.topic, message.publish_time)
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
        except _READ_ERRORS as exc:
            raise _unreadable(path, exc) from exc


def iter_attachments(path: str | Path) -> Iterator[tuple[str, str, bytes]]:
    """``(name, media_type, data)`` of every attachment."""
    with _open(path) as stream:
        try:
            for att in make_reader(stream).iter_attachments():
                yield att.name, att.media_type, att.data
        except _READ_ERRORS as exc:
            raise _unreadable(path, exc) from exc


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
            attachments = [a.name[:200] for a in reader.iter_attachments()]
        except _READ_ERRORS as exc:
            raise _unreadable(path, exc) from exc
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


def _check_encodings(path: str | Path, info: FileInfo) -> None:
    for topic in ("/scan", "/cmd_vel"):
        got = info.channels.get(topic)
        if got is not None and got[1] != "json":
            raise LogError(
                f"{path}: {topic} is {got[1] or 'unknown'}-encoded {got[0] or 'data'}, not an lfdfuse log:"
                f" run `lfdfuse import {path}` first"
            )


def read_run(path: str | Path) -> Run:
    """Load an lfdfuse log (simulated, executed or imported) into arrays.

    Memory is the arrays themselves (scans are decoded one message at a time into a
    preallocated ``(N, B)`` array); every malformed message is a :class:`LogError` naming it.
    """
    info = file_info(path)
    _check_encodings(path, info)
    counts = {topic: n for topic, (_s, _e, n) in info.channels.items()}
    scans: _Rows | None = None
    scan_t: list[int] = []
    sonars: _Rows | None = None
    sonar_t: list[int] = []
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
    for topic, _schema, enc, t_ns, data in _iter(path, ["/scan", "/sonar", "/pose", "/cmd_vel", "/targets"]):
        if enc != "json":
            raise LogError(
                f"{path}: {topic} is {enc or 'unknown'}-encoded: run `lfdfuse import {path}` first"
            )
        topics.add(topic)
        msg = _json(path, topic, t_ns, data)
        try:
            if topic == "/scan":
                scan = decode_scan(msg)
                row = _ranges(path, topic, t_ns, scan)
                if scans is None:
                    first_scan, scans = scan, _Rows(len(row), counts.get(topic, 0))
                elif len(row) != scans.data.shape[1]:
                    raise LogError(
                        f"{path}: /scan messages have different beam counts ({scans.data.shape[1]} and {len(row)})"
                    )
                scans.append(row)
                scan_t.append(t_ns)
            elif topic == "/sonar":
                sonar = decode_scan(msg)
                row = _ranges(path, topic, t_ns, sonar)
                if sonars is None:
                    first_sonar, sonars = sonar, _Rows(len(row), counts.get(topic, 0))
                elif len(row) != sonars.data.shape[1]:
                    raise LogError(f"{path}: /sonar messages have different beam counts")
                sonars.append(row)
                sonar_t.append(t_ns)
            elif topic == "/pose":
                pose_t.append(t_ns)
                poses.append(decode_pose(msg))
            elif topic == "/cmd_vel":
                cmd_t.append(t_ns)
                cmds.append(decode_twist(msg))
            elif topic == "/targets":
                dets.append((t_ns, _detections(path, t_ns, msg)))
        except _DECODE_ERRORS as exc:
            raise LogError(
                f"{path}: a {topic} message at t={t_ns} ns is malformed ({exc.__class__.__name__}: {exc})"
            ) from exc
    missing = [t for t in ("/scan", "/cmd_vel") if t not in topics]
    if missing:
        raise LogError(f"{path}: the log has no {' and no '.join(missing)} messages")
    assert first_scan is not None and scans is not None
    t = np.array(scan_t, dtype=np.int64)
    ranges = scans.array()
    del scans
    meta: dict[str, str] = info.metadata.get(PROVENANCE, {})
    # without our metadata the max range is unknown: then no range counts as a sentinel (inf), which
    # is harmless to the primitives, which only look at returns nearer than d_max
    max_range = meta_float(meta, "laser_max_range_m", math.inf, path=path)
    geom = scan_geometry(first_scan, ranges.shape[1], max_range)
    cmd = np.array(cmds, dtype=np.float64).reshape(-1, 2)
    run_kwargs: dict[str, Any] = {}
    if sonars is not None and first_sonar is not None:
        st = np.array(sonar_t, dtype=np.int64)
        sr = sonars.array()
        run_kwargs["sonar_m"] = sr[hold(st, t)]
        run_kwargs["sonar_geometry"] = scan_geometry(
            first_sonar, sr.shape[1], meta_float(meta, "sonar_max_range_m", math.inf, path=path)
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
    return Run(
        t_ns=t,
        geometry=geom,
        ranges_m=ranges,
        cmd_t_ns=np.array(cmd_t, dtype=np.int64),
        cmd_v_mps=cmd[:, 0],
        cmd_omega_rps=cmd[:, 1],
        metadata=meta,
        world_yaml=_world_attachment(path) if "world.yaml" in info.attachments else None,
        topics=tuple(sorted(topics)),
        **run_kwargs,
    )


def _world_attachment(path: str | Path) -> str | None:
    """The attached world file's text; None when absent, too big or not text (it is only a hint)."""
    for name, _media, data in iter_attachments(path):
        if name == "world.yaml" and len(data) <= MAX_WORLD_BYTES:
            try:
                return data.decode("utf-8")
            except UnicodeDecodeError:
                return None
    return None


__all__ = [
    "MAX_BEAMS",
    "FileInfo",
    "RawMessage",
    "Run",
    "file_info",
    "from_stamp",
    "hold",
    "iter_attachments",
    "iter_messages",
    "iter_raw",
    "check_log_file",
    "read_run",
]
