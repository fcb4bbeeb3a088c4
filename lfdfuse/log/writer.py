"""The MCAP writer: a context manager that writes atomically (temp file + rename)."""

from __future__ import annotations

import contextlib
import itertools
import os
import struct
from collections.abc import Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, BinaryIO

import orjson
from mcap.records import MessageIndex
from mcap.writer import CompressionType, Writer

from lfdfuse import __version__
from lfdfuse.errors import LogError
from lfdfuse.files import TempBeside, umask
from lfdfuse.log.chunks import BackgroundChunks
from lfdfuse.log.messages import PROVENANCE, TOPICS, RawMessage
from lfdfuse.log.schemas import schema_text

__all__ = ["PROVENANCE", "LogWriter"]

#: a chunk is compressed and written once its records pass this many bytes
CHUNK_SIZE = 4 * 1024 * 1024
#: a Message record's head: opcode, record length, channel, sequence, log time, publish time
_MESSAGE_HEAD = struct.Struct("<BQHIQQ")
_MESSAGE_OPCODE = 0x05
#: a MessageIndex record's head: opcode, record length, channel, length of the records
_INDEX_HEAD = struct.Struct("<BQHI")
_INDEX_OPCODE = 0x07


class _Messages:
    """``Writer.add_message`` of mcap in one step: the same statistics, chunk index and record
    bytes, without the per-field writes that made it the largest cost of a simulated tick.

    Built on the writer's private state; :meth:`of` gives None when this mcap version does not
    have it, and the public ``add_message`` is used instead.
    """

    def __init__(self, writer: Writer) -> None:
        self.writer = writer
        self.stats = writer._Writer__statistics  # type: ignore[attr-defined]
        self.chunk = writer._Writer__chunk_builder  # type: ignore[attr-defined]
        self.limit = writer._Writer__chunk_size  # type: ignore[attr-defined]
        self.finalize = writer._Writer__finalize_chunk  # type: ignore[attr-defined]
        self.last_ns: int | None = None  # the time of the last message added
        buffer = self.chunk.record_writer._buffer
        assert hasattr(buffer, "write") and hasattr(buffer, "tell")
        assert isinstance(self.chunk.message_indices, dict) and isinstance(self.chunk.num_messages, int)
        assert isinstance(self.stats.channel_message_counts, dict) and isinstance(self.limit, int)

    @classmethod
    def of(cls, writer: Writer) -> _Messages | None:
        try:
            return cls(writer)
        except (AttributeError, AssertionError):
            return None

    def add(
        self, channel_id: int, t_ns: int, data: bytes, sequence: int, publish_ns: int | None = None
    ) -> None:
        stats, chunk = self.stats, self.chunk
        if t_ns != self.last_ns or chunk.num_messages == 0:
            # the min and max of the times so far, as comparisons (integers: the same numbers);
            # a message at the time of the last one in this chunk changes none of them
            if stats.message_count == 0 or t_ns < stats.message_start_time:
                stats.message_start_time = t_ns
            if t_ns > stats.message_end_time:
                stats.message_end_time = t_ns
            if chunk.num_messages == 0 or t_ns < chunk.message_start_time:
                chunk.message_start_time = t_ns
            if t_ns > chunk.message_end_time:
                chunk.message_end_time = t_ns
            self.last_ns = t_ns
        stats.channel_message_counts[channel_id] += 1
        stats.message_count += 1
        buffer = chunk.record_writer._buffer
        at = buffer.tell()
        index = chunk.message_indices.get(channel_id)
        if index is None:
            index = chunk.message_indices[channel_id] = _Index(channel_id=channel_id, records=[])
        index.records.append((t_ns, at))
        chunk.num_messages += 1
        published = t_ns if publish_ns is None else publish_ns
        buffer.write(
            _MESSAGE_HEAD.pack(_MESSAGE_OPCODE, 22 + len(data), channel_id, sequence, t_ns, published) + data
        )
        if at + 31 + len(data) > self.limit:  # the head is 31 bytes
            self.finalize()

    def add_tick(self, t_ns: int, entries: list[tuple[int, int, bytes]]) -> None:
        """:meth:`add` of each ``(channel, sequence, data)`` at ``t_ns`` in turn (the same bytes and
        chunks), written in one piece up to the message that fills a chunk, and so on."""
        stats, chunk = self.stats, self.chunk
        if t_ns != self.last_ns or chunk.num_messages == 0:
            channel_id, sequence, data = entries[0]
            self.add(channel_id, t_ns, data, sequence)  # the times updated, as one message does
            if len(entries) > 1:
                self.add_tick(t_ns, entries[1:])
            return
        counts, indices = stats.channel_message_counts, chunk.message_indices
        buffer = chunk.record_writer._buffer
        at = buffer.tell()
        parts: list[bytes] = []
        head = _MESSAGE_HEAD.pack
        for i, (channel_id, sequence, data) in enumerate(entries):
            counts[channel_id] += 1
            index = indices.get(channel_id)
            if index is None:
                index = indices[channel_id] = _Index(channel_id=channel_id, records=[])
            index.records.append((t_ns, at))
            parts += (head(_MESSAGE_OPCODE, 22 + len(data), channel_id, sequence, t_ns, t_ns), data)
            at += 31 + len(data)  # the head is 31 bytes
            if at > self.limit:  # this message fills the chunk: the rest go into the next
                stats.message_count += i + 1
                chunk.num_messages += i + 1
                buffer.write(b"".join(parts))
                self.finalize()
                if i + 1 < len(entries):
                    self.add_tick(t_ns, entries[i + 1 :])
                return
        stats.message_count += len(entries)
        chunk.num_messages += len(entries)
        buffer.write(b"".join(parts))


class _Index(MessageIndex):
    """A chunk's index of one channel's messages: :meth:`MessageIndex.write`'s bytes in two
    writes instead of two per message (a chunk of a long run indexes tens of thousands)."""

    def write(self, stream: Any) -> None:
        n = len(self.records)
        stream.write(_INDEX_HEAD.pack(_INDEX_OPCODE, 6 + 16 * n, self.channel_id, 16 * n))
        stream.write(struct.pack(f"<{2 * n}Q", *itertools.chain.from_iterable(self.records)))


class LogWriter:
    """Writes JSON messages to an MCAP file, atomically.

    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "x.mcap")
    >>> with LogWriter(p, metadata={"seed": "1"}) as log:
    ...     log.write("/cmd_vel", 0, {"timestamp": {"sec": 0, "nsec": 0}, "linear": {"x": 0.1}, "angular": {"z": 0.0}})
    >>> os.path.getsize(p) > 0
    True
    """

    def __init__(
        self, path: str | Path, *, metadata: dict[str, str], topics: dict[str, str] | None = None
    ) -> None:
        self.path = Path(path)
        self.metadata = metadata
        self.topics = dict(TOPICS) if topics is None else topics
        self._stream: BinaryIO | None = None
        self._tmp = TempBeside(self.path)
        self._writer: Writer | None = None
        self._schemas: dict[Any, int] = {}
        self._channels: dict[str, int] = {}
        self._seq: dict[str, int] = {}
        self._messages: _Messages | None = None
        self._chunks: BackgroundChunks | None = None

    def __enter__(self) -> LogWriter:
        parent = self.path.parent if str(self.path.parent) else Path(".")
        if not parent.is_dir():
            raise LogError(f"cannot write {self.path}: folder {parent} does not exist")
        fd = -1
        try:
            fd = self._tmp.open()
            self._stream = os.fdopen(fd, "wb")
            self._writer = Writer(self._stream, compression=CompressionType.ZSTD, chunk_size=CHUNK_SIZE)
            self._writer.start(profile="", library=f"lfdfuse {__version__}")
            # full chunks compressed beside the run (before _Messages, which calls the finaliser)
            self._chunks = BackgroundChunks.of(self._writer)
            self._messages = _Messages.of(self._writer)
        except BaseException as exc:
            # interrupted here (SIGTERM as the command starts), __exit__ never runs: clean up now
            # (the temp file's name is known before it is made: whenever the signal came, it goes)
            if self._stream is not None:
                self._stream.close()
            elif fd >= 0:
                os.close(fd)
            self._tmp.remove()
            if isinstance(exc, OSError):
                raise LogError(f"cannot write {self.path}: {exc.strerror}") from exc
            raise
        return self

    def add_topic(self, topic: str, schema_name: str) -> None:
        self.topics[topic] = schema_name

    def _channel(self, topic: str) -> int:
        ch = self._channels.get(topic)
        if ch is not None:
            return ch
        assert self._writer is not None
        name = self.topics.get(topic)
        if name is None:
            raise KeyError(f"topic {topic} has no schema registered")
        sid = self._schemas.get(name)
        if sid is None:
            sid = self._writer.register_schema(name=name, encoding="jsonschema", data=schema_text(name))
            self._schemas[name] = sid
        ch = self._writer.register_channel(topic=topic, message_encoding="json", schema_id=sid)
        self._channels[topic] = ch
        self._seq[topic] = 0
        return ch

    def write(self, topic: str, t_ns: int, message: dict[str, Any]) -> None:
        self.write_raw(topic, t_ns, orjson.dumps(message))

    def write_raw(self, topic: str, t_ns: int, data: bytes) -> None:
        assert self._writer is not None, "LogWriter used outside its with-block"
        ch = self._channels.get(topic)
        if ch is None:
            ch = self._channel(topic)
        seq = self._seq[topic] = self._seq[topic] + 1
        if self._messages is not None:
            self._messages.add(ch, t_ns, data, seq)
        else:
            self._writer.add_message(channel_id=ch, log_time=t_ns, publish_time=t_ns, data=data, sequence=seq)

    def write_tick(self, t_ns: int, messages: Sequence[tuple[str, bytes]]) -> None:
        """:meth:`write_raw` of each ``(topic, data)`` at ``t_ns``, in order (the same bytes)."""
        assert self._writer is not None, "LogWriter used outside its with-block"
        if self._messages is None or not messages:
            for topic, data in messages:
                self.write_raw(topic, t_ns, data)
            return
        channels, seqs, add_tick = self._channels, self._seq, self._messages.add_tick
        entries: list[tuple[int, int, bytes]] = []
        for topic, data in messages:
            ch = channels.get(topic)
            if ch is None:  # a new channel: its record goes into the chunk before this message
                if entries:
                    add_tick(t_ns, entries)
                    entries = []
                self.write_raw(topic, t_ns, data)
                continue
            seq = seqs[topic] = seqs[topic] + 1
            entries.append((ch, seq, data))
        if entries:
            add_tick(t_ns, entries)

    def copy(self, raw: RawMessage) -> None:
        """Write a message read from another file, keeping its channel and schema as they were."""
        assert self._writer is not None
        key = f"{raw.topic}\0{raw.schema_name}\0{raw.message_encoding}"
        ch = self._channels.get(key)
        if ch is None:
            skey = (raw.schema_name, raw.schema_encoding, raw.schema_data)
            sid = self._schemas.get(skey)
            if sid is None:
                sid = (
                    self._writer.register_schema(
                        name=raw.schema_name, encoding=raw.schema_encoding, data=raw.schema_data
                    )
                    if raw.schema_name
                    else 0
                )
                self._schemas[skey] = sid
            ch = self._writer.register_channel(
                topic=raw.topic, message_encoding=raw.message_encoding, schema_id=sid
            )
            self._channels[key] = ch
            self._seq[key] = 0
        seq = self._seq[key] = self._seq[key] + 1
        if self._messages is not None:
            self._messages.add(ch, raw.log_time_ns, raw.data, seq, raw.publish_time_ns)
        else:
            self._writer.add_message(
                channel_id=ch,
                log_time=raw.log_time_ns,
                publish_time=raw.publish_time_ns,
                data=raw.data,
                sequence=seq,
            )

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        """An extra metadata record (the provenance record is written on close)."""
        assert self._writer is not None
        self._writer.add_metadata(name, data)

    def attach(self, name: str, media_type: str, data: bytes) -> None:
        assert self._writer is not None
        self._writer.add_attachment(create_time=0, log_time=0, name=name, media_type=media_type, data=data)

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        assert self._writer is not None and self._stream is not None
        try:
            if exc_type is None:
                self._writer.add_metadata(PROVENANCE, dict(sorted(self.metadata.items())))
                self._writer.finish()
            self._stream.close()
            if exc_type is None:
                os.chmod(self._tmp.name, 0o666 & ~umask())
                os.replace(self._tmp.name, self.path)
        except OSError as err:
            raise LogError(f"cannot write {self.path}: {err.strerror}") from err
        finally:
            if self._chunks is not None:
                self._chunks.close()  # joins a compression a failed finish left running
            if not self._stream.closed:  # finish failed: the file is dropped, its error kept
                with contextlib.suppress(OSError):
                    self._stream.close()
            self._tmp.remove()
