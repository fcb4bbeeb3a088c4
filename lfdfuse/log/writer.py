"""The MCAP writer: a context manager that writes atomically (temp file + rename)."""

from __future__ import annotations

import os
import struct
import tempfile
from pathlib import Path
from types import TracebackType
from typing import Any, BinaryIO

import orjson
from mcap._chunk_builder import ChunkBuilder
from mcap.records import Message, MessageIndex
from mcap.writer import CompressionType, Writer

from lfdfuse import __version__
from lfdfuse.errors import LogError
from lfdfuse.files import umask
from lfdfuse.log.messages import PROVENANCE, TOPICS, RawMessage
from lfdfuse.log.schemas import schema_text

__all__ = ["PROVENANCE", "LogWriter"]

#: a Message record's opcode, length, channel, sequence, log and publish time (MCAP spec)
_MESSAGE_HEAD = struct.Struct("<BQHIQQ")
_MESSAGE_OPCODE = 0x05


class _ChunkBuilder(ChunkBuilder):
    """mcap's chunk builder with a message record packed at once, not field by field and
    length patched afterwards: the same bytes, a third of the time of a log's writing."""

    def add_message(self, message: Message) -> None:
        if self.num_messages == 0:
            self.message_start_time = message.log_time
        else:
            self.message_start_time = min(self.message_start_time, message.log_time)
        self.message_end_time = max(self.message_end_time, message.log_time)
        index = self.message_indices.get(message.channel_id)
        if not index:
            index = self.message_indices[message.channel_id] = MessageIndex(message.channel_id, [])
        buf = self.record_writer._buffer
        index.records.append((message.log_time, buf.tell()))
        self.num_messages += 1
        data = message.data
        buf.write(
            _MESSAGE_HEAD.pack(
                _MESSAGE_OPCODE,
                22 + len(data),
                message.channel_id,
                message.sequence,
                message.log_time,
                message.publish_time,
            )
        )
        buf.write(data)


def _fast_messages(writer: Writer) -> None:
    """Give ``writer`` the :class:`_ChunkBuilder` where this mcap version has the builder it
    replaces (else the writer is left as it is: slower, the same file)."""
    if type(getattr(writer, "_Writer__chunk_builder", None)) is ChunkBuilder:
        writer._Writer__chunk_builder = _ChunkBuilder()  # type: ignore[attr-defined]


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
        self._tmp = ""
        self._writer: Writer | None = None
        self._schemas: dict[Any, int] = {}
        self._channels: dict[str, int] = {}
        self._seq: dict[str, int] = {}

    def __enter__(self) -> LogWriter:
        parent = self.path.parent if str(self.path.parent) else Path(".")
        if not parent.is_dir():
            raise LogError(f"cannot write {self.path}: folder {parent} does not exist")
        try:
            fd, self._tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".tmp", dir=parent)
        except OSError as exc:
            raise LogError(f"cannot write {self.path}: {exc.strerror}") from exc
        try:
            self._stream = os.fdopen(fd, "wb")
            self._writer = Writer(self._stream, compression=CompressionType.ZSTD, chunk_size=4 * 1024 * 1024)
            _fast_messages(self._writer)
            self._writer.start(profile="", library=f"lfdfuse {__version__}")
        except BaseException:
            # interrupted here (SIGTERM as the command starts), __exit__ never runs: clean up now
            if self._stream is not None:
                self._stream.close()
            else:
                os.close(fd)
            os.unlink(self._tmp)
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
        ch = self._channel(topic)
        self._seq[topic] += 1
        self._writer.add_message(
            channel_id=ch, log_time=t_ns, publish_time=t_ns, data=data, sequence=self._seq[topic]
        )

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
        self._seq[key] += 1
        self._writer.add_message(
            channel_id=ch,
            log_time=raw.log_time_ns,
            publish_time=raw.publish_time_ns,
            data=raw.data,
            sequence=self._seq[key],
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
                os.chmod(self._tmp, 0o666 & ~umask())
                os.replace(self._tmp, self.path)
        except OSError as err:
            raise LogError(f"cannot write {self.path}: {err.strerror}") from err
        finally:
            if os.path.exists(self._tmp):
                os.unlink(self._tmp)
