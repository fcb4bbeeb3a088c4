"""An indexed MCAP file's messages in log-time order, chunk by chunk.

mcap's reader orders messages with a heap whose every comparison is Python code; on a demo of
an hour that is most of the time ``segment`` spends reading. Files written in time order (ours,
and most recorders') have chunks whose time ranges follow one another: then log-time order is
each chunk's messages sorted by time, chunk after chunk — the same order as mcap's (time, then
position in the file), found by one sort per chunk. Any other file (no chunk index, chunks that
overlap in time, a compression we do not read) goes through mcap's reader as before.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator, Sequence
from typing import Any

import zstandard
from mcap.exceptions import McapError

#: one message as the readers use it: (schema or None, channel, log time, publish time, data)
Item = tuple[Any, Any, int, int, bytes]

_MESSAGE = 0x05
_RECORD = struct.Struct("<BQ")
_MESSAGE_HEAD = struct.Struct("<HIQQ")
_CHUNK_HEAD = struct.Struct("<QQQII")


def in_log_time_order(reader: Any, stream: Any, topics: Sequence[str] | None = None) -> Iterator[Item]:
    """Every message of ``reader``'s file (of ``topics``, or all) in log-time order; ties in the
    order they are in the file (what ``reader.iter_messages(log_time_order=True)`` yields)."""
    chunks = _sequential_chunks(reader, topics)
    if chunks is None:
        for schema, channel, m in reader.iter_messages(topics=topics, log_time_order=True):
            yield schema, channel, m.log_time, m.publish_time, m.data
        return
    summary = reader.get_summary()
    wanted = None if topics is None else set(topics)
    for index in chunks:
        yield from _chunk_messages(stream, index, summary, wanted)


def _sequential_chunks(reader: Any, topics: Sequence[str] | None) -> list[Any] | None:
    """The chunk indexes in reading order when each chunk's messages all come after the previous
    chunk's (by time, a tie by file position); None when mcap's own ordering is needed."""
    summary = reader.get_summary()
    if summary is None or not summary.chunk_indexes:
        return None
    wanted = None if topics is None else set(topics)
    chunks = [
        c
        for c in summary.chunk_indexes
        if wanted is None
        or not c.message_index_offsets
        or any(summary.channels[i].topic in wanted for i in c.message_index_offsets if i in summary.channels)
    ]
    chunks.sort(key=lambda c: (c.message_start_time, c.chunk_start_offset))
    for a, b in zip(chunks, chunks[1:], strict=False):
        after = a.message_end_time < b.message_start_time or (
            a.message_end_time == b.message_start_time and a.chunk_start_offset < b.chunk_start_offset
        )
        if not after:
            return None
    if any(c.compression not in ("zstd", "") for c in chunks):
        return None
    return chunks


def _chunk_messages(stream: Any, index: Any, summary: Any, wanted: set[str] | None) -> Iterator[Item]:
    stream.seek(index.chunk_start_offset)
    head = stream.read(9)
    if len(head) < 9:
        raise McapError(f"a chunk at byte {index.chunk_start_offset} is cut short")
    _op, length = _RECORD.unpack(head)
    body = stream.read(length)
    if len(body) < length or length < _CHUNK_HEAD.size + 8:
        raise McapError(f"a chunk at byte {index.chunk_start_offset} is cut short")
    _start, _end, size, _crc, name_len = _CHUNK_HEAD.unpack_from(body)
    at = _CHUNK_HEAD.size + name_len
    compression = body[_CHUNK_HEAD.size : at].decode("utf-8", "replace")
    (data_len,) = struct.unpack_from("<Q", body, at)
    data = body[at + 8 : at + 8 + data_len]
    if compression == "zstd":
        data = zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    elif compression:
        raise McapError(f"unsupported compression {compression!r}")
    channels, schemas = summary.channels, summary.schemas
    found: list[tuple[int, int, Item]] = []
    pos, end = 0, len(data)
    while pos + 9 <= end:
        op, n = _RECORD.unpack_from(data, pos)
        pos += 9
        if pos + n > end:
            raise McapError(f"a record in the chunk at byte {index.chunk_start_offset} runs past its end")
        if op == _MESSAGE:
            if n < _MESSAGE_HEAD.size:
                raise McapError(f"a message in the chunk at byte {index.chunk_start_offset} is cut short")
            channel_id, _seq, log_time, publish_time = _MESSAGE_HEAD.unpack_from(data, pos)
            channel = channels[channel_id]  # an unknown channel: KeyError, as mcap's reader raises
            if wanted is None or channel.topic in wanted:
                schema = schemas[channel.schema_id] if channel.schema_id else None
                item = (schema, channel, log_time, publish_time, data[pos + _MESSAGE_HEAD.size : pos + n])
                found.append((log_time, len(found), item))
        pos += n
    found.sort(key=lambda f: (f[0], f[1]))
    if found and (found[0][0] < index.message_start_time or found[-1][0] > index.message_end_time):
        raise McapError(
            f"the chunk at byte {index.chunk_start_offset} holds messages outside the time range its index gives"
        )
    for _t, _i, item in found:
        yield item
