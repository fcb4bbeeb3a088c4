"""The MCAP reader: messages as a generator, and a whole run loaded into arrays."""

from __future__ import annotations

import io
import os
import stat
import struct
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import zstandard
from mcap.exceptions import McapError
from mcap.reader import make_reader

from lfdfuse.errors import LogError
from lfdfuse.log.messages import PROVENANCE, RawMessage, from_stamp
from lfdfuse.log.run import MAX_BEAMS, RUN_TOPICS, Run, RunBuilder, hold, meta_float
from lfdfuse.log.stamps import check_log_time
from lfdfuse.progress import Progress, tell

#: the first bytes of every MCAP file
MCAP_MAGIC = b"\x89MCAP0\r\n"
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
_HEADER, _CHUNK, _DATA_END, _FOOTER = 0x01, 0x06, 0x0F, 0x02


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
        if pos == len(MCAP_MAGIC) and opcode != _HEADER:
            raise LogError(f"{p}: not a readable MCAP file (no header record after the magic bytes)")
        if opcode == 0:
            raise LogError(f"{p}: not a readable MCAP file (a record at byte {pos} has opcode 0)")
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
    size = stream._size
    stream.seek(max(len(MCAP_MAGIC), size - len(MCAP_MAGIC)))
    if size < 2 * len(MCAP_MAGIC) or stream.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
        stream.close()
        raise LogError(
            f"{p}: not a readable MCAP file (truncated MCAP file: it ends at byte {size} without the closing"
            " magic bytes, cut short while written or copied): copy it again, or keep its readable part"
            " with `mcap recover`"
        )
    stream.seek(len(MCAP_MAGIC))
    try:
        _check_chunks(p, stream)
    except BaseException:
        stream.close()
        raise
    return stream


def _unreadable(path: str | Path, exc: BaseException) -> LogError:
    text = str(exc).splitlines()[0][:120] if str(exc) else exc.__class__.__name__
    return LogError(f"{path}: not a readable MCAP file (damaged: {text})")


def iter_records(
    path: str | Path, *, topics: Sequence[str] | None = None, check_times: bool = True
) -> Iterator[tuple[str, str, str, int, bytes]]:
    """``(topic, schema name, message encoding, log time ns, data)`` in log-time order: one pass
    over the file's messages (of ``topics``, or all).

    ``check_times=False`` leaves the int64 check of each log time to the caller, who feeds the
    messages to readers that check their own (:meth:`lfdfuse.log.run.RunBuilder.feed`): then one
    reader's bad time is its error, not the whole pass's.
    """
    with _open(path) as stream:
        try:
            reader = make_reader(stream)
            wanted = None if topics is None else list(topics)
            for schema, channel, message in reader.iter_messages(topics=wanted, log_time_order=True):
                if check_times:
                    check_log_time(path, channel.topic, message.log_time)
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
    for topic, schema, _enc, t, data in iter_records(path, topics=topics):
        yield topic, schema, t, data


def iter_raw(path: str | Path, *, exclude_prefix: str | None = None) -> Iterator[RawMessage]:
    """Every message of a file in log-time order, optionally without topics under a prefix."""
    with _open(path) as stream:
        try:
            reader = make_reader(stream)
            for schema, channel, message in reader.iter_messages(log_time_order=True):
                if exclude_prefix is not None and channel.topic.startswith(exclude_prefix):
                    continue
                check_log_time(path, channel.topic, message.log_time)
                check_log_time(path, channel.topic, message.publish_time)
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


def read_run(path: str | Path, *, progress: Progress | None = None) -> Run:
    """Load an lfdfuse log (simulated, executed or imported) into arrays: its summary, one pass
    over its :data:`~lfdfuse.log.run.RUN_TOPICS` (:class:`~lfdfuse.log.run.RunBuilder`), and the
    attached world file. Every malformed message is a :class:`LogError` naming it. ``progress``
    hears how far into the log's time span the pass is.
    """
    info = file_info(path)
    builder = run_builder(path, info)
    span = max(info.end_ns - info.start_ns, 1)
    for i, (topic, _schema, enc, t_ns, data) in enumerate(
        iter_records(path, topics=RUN_TOPICS, check_times=False)
    ):
        builder.feed(topic, enc, t_ns, data)
        if progress is not None and i % 512 == 0:
            tell(progress, min(max(t_ns - info.start_ns, 0), span), span)
    tell(progress, span, span)
    return finish_run(path, info, builder)


def run_builder(path: str | Path, info: FileInfo) -> RunBuilder:
    """A builder for the run of ``path``, whose summary is ``info`` (a :class:`LogError` when its
    scans or commands are not ours: a robot log to import first)."""
    return RunBuilder(path, channels=info.channels, metadata=info.metadata.get(PROVENANCE, {}))


def finish_run(path: str | Path, info: FileInfo, builder: RunBuilder) -> Run:
    """The run ``builder`` was fed, with the world file attached to ``path`` (read last: only a hint)."""
    run = builder.finish()
    return replace(run, world_yaml=_world_attachment(path) if "world.yaml" in info.attachments else None)


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
    "RUN_TOPICS",
    "FileInfo",
    "RawMessage",
    "Run",
    "RunBuilder",
    "check_log_file",
    "file_info",
    "finish_run",
    "from_stamp",
    "hold",
    "iter_attachments",
    "iter_messages",
    "iter_raw",
    "iter_records",
    "meta_float",
    "read_run",
    "run_builder",
]
