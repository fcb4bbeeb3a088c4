"""A writer's chunks compressed on a background thread: the same file, less of the run's time.

mcap's ``Writer`` compresses a chunk where it fills, inside the call that added the message that
filled it: a long run stops for milliseconds every 4 MiB to zstd-compress them. zstandard (and
zlib's CRC) release the GIL, so on a second core the compression overlaps the ticks that follow.
:class:`BackgroundChunks` takes over the writer's private chunk finalising: a full chunk's bytes
are handed to a thread, and its records (the chunk, its message indexes, its chunk index) are
written when the next chunk fills or anything else reaches the file. The chunks go in the same
order, with the same bytes, at the same offsets: only *when* the compression runs changes.
:meth:`BackgroundChunks.close` joins the thread; a compression's error is raised by the write
that waits for it (at the latest on close), never lost.
"""

from __future__ import annotations

import threading
import zlib
from dataclasses import dataclass, field

import zstandard
from mcap.data_stream import RecordBuilder
from mcap.records import Chunk, ChunkIndex, MessageIndex
from mcap.writer import CompressionType, IndexType, Writer

__all__ = ["BackgroundChunks"]


def _compress(data: bytes) -> tuple[bytes, int]:
    """What mcap's writer computes of a full chunk: its zstd frame and its CRC."""
    return zstandard.compress(data), zlib.crc32(data)


@dataclass
class _Pending:
    """A chunk handed to the thread: what its records need besides the compressed bytes."""

    data: bytes
    start_ns: int
    end_ns: int
    indices: dict[int, MessageIndex]
    thread: threading.Thread = field(init=False)
    result: tuple[bytes, int] | None = None
    error: BaseException | None = None

    def __post_init__(self) -> None:
        self.thread = threading.Thread(target=self._run, name="mcap-chunk", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            self.result = _compress(self.data)
        except BaseException as exc:  # raised in the writing thread by wait()
            self.error = exc

    def wait(self) -> tuple[bytes, int]:
        self.thread.join()
        if self.error is not None:
            raise self.error
        assert self.result is not None
        return self.result


class BackgroundChunks:
    """Installs itself as ``writer``'s chunk finaliser and record flusher (see the module
    docstring). Built on the writer's private state, as the writer's defaults set it (zstd,
    CRCs of chunks, no CRC of the data section, every index): :meth:`of` gives None otherwise,
    and the writer compresses in place as before."""

    def __init__(self, writer: Writer) -> None:
        self.builder = writer._Writer__chunk_builder  # type: ignore[attr-defined]
        self.stats = writer._Writer__statistics  # type: ignore[attr-defined]
        self.chunk_indices: list[ChunkIndex] = writer._Writer__chunk_indices  # type: ignore[attr-defined]
        self.stream = writer._Writer__stream  # type: ignore[attr-defined]
        self.flush_records = writer._Writer__flush  # type: ignore[attr-defined]
        assert self.builder is not None and isinstance(self.chunk_indices, list)
        assert writer._Writer__compression == CompressionType.ZSTD  # type: ignore[attr-defined]
        assert writer._Writer__enable_crcs is True  # type: ignore[attr-defined]
        assert writer._Writer__enable_data_crcs is False  # type: ignore[attr-defined]
        assert writer._Writer__index_types & IndexType.MESSAGE  # type: ignore[attr-defined]
        assert hasattr(self.stream, "tell") and hasattr(self.builder, "message_indices")
        self.pending: list[_Pending] = []
        # the instance's attributes are looked up before the class's private methods
        writer._Writer__finalize_chunk = self.finalize  # type: ignore[attr-defined]
        writer._Writer__flush = self.flush  # type: ignore[attr-defined]

    @classmethod
    def of(cls, writer: Writer) -> BackgroundChunks | None:
        try:
            return cls(writer)
        except (AttributeError, AssertionError):
            return None

    def finalize(self) -> None:
        """The writer's chunk finalising: the chunk handed to the thread, the one before written."""
        b = self.builder
        if b.num_messages == 0:
            return
        self.stats.chunk_count += 1
        self.write_pending()
        self.pending.append(
            _Pending(b.end(), b.message_start_time, b.message_end_time, dict(b.message_indices))
        )
        b.reset()

    def flush(self) -> None:
        """The writer's record flush: the chunks handed off go first, as they came first."""
        self.write_pending()
        self.flush_records()

    def write_pending(self) -> None:
        """Wait for the chunks handed off and write their records, as mcap's writer writes them."""
        while self.pending:
            p = self.pending.pop(0)
            compressed, crc = p.wait()
            chunk = Chunk(
                compression="zstd",
                data=compressed,
                message_start_time=p.start_ns,
                message_end_time=p.end_ns,
                uncompressed_crc=crc,
                uncompressed_size=len(p.data),
            )
            records = RecordBuilder()
            start = self.stream.tell()
            chunk.write(records)
            index = ChunkIndex(
                message_start_time=p.start_ns,
                message_end_time=p.end_ns,
                chunk_start_offset=start,
                chunk_length=records.count,
                message_index_offsets={},
                message_index_length=0,
                compression="zstd",
                compressed_size=len(compressed),
                uncompressed_size=len(p.data),
            )
            for channel_id, message_index in p.indices.items():
                index.message_index_offsets[channel_id] = start + records.count
                message_index.write(records)
            index.message_index_length = records.count - index.chunk_length
            self.stream.write(records.end())
            self.chunk_indices.append(index)

    def close(self) -> None:
        """Join every thread without writing (a run that failed leaves no file to finish)."""
        for p in self.pending:
            p.thread.join()
        self.pending.clear()
