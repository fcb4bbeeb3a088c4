"""Chunks compressed on a background thread: the file mcap's own writer writes, byte for byte,
and a compression's error raised on close, never lost."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lfdfuse.log import chunks, writer
from lfdfuse.log.reader import iter_raw
from lfdfuse.log.writer import LogWriter

#: a message (topic, time, bytes), or an attachment or a metadata record between messages: the
#: records outside chunks, which must follow the chunks handed to the thread before them
events = st.lists(
    st.one_of(
        st.tuples(
            st.sampled_from(["/cmd_vel", "/scan", "/pose"]),
            st.one_of(st.integers(0, 5), st.integers(0, 2**63 - 1)),
            st.binary(max_size=300),
        ),
        st.tuples(st.sampled_from(["attach", "metadata"]), st.integers(0, 9), st.binary(max_size=40)),
    ),
    max_size=60,
)


def _write(path: Path, events: list[tuple[str, int, bytes]]) -> LogWriter:
    with LogWriter(path, metadata={"seed": "1"}) as log:
        for what, t, data in events:
            if what == "attach":
                log.attach(f"a{t}.bin", "application/octet-stream", data)
            elif what == "metadata":
                log.add_metadata(f"m{t}", {"k": data.hex()})
            else:
                log.write_raw(what, t, data)
    return log


def _ways(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, write: Callable[[Path], LogWriter]) -> list[bytes]:
    """The file ``write`` makes with chunks compressed on the thread, and with mcap's own (in place)."""
    files = []
    for way in ("thread", "mcap"):
        with monkeypatch.context() as m:
            if way == "mcap":
                m.setattr(writer.BackgroundChunks, "of", classmethod(lambda cls, w: None))
            path = tmp_path / f"{way}.mcap"
            log = write(path)
            assert (log._chunks is not None) == (way == "thread")
            files.append(path.read_bytes())
    return files


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(events, st.integers(64, 2000))
def test_a_file_with_chunks_compressed_beside_the_run_is_mcaps_byte_for_byte(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, events: list[tuple[str, int, bytes]], chunk_size: int
) -> None:
    # chunks of a few hundred bytes: a handful fill in one example, with records between them
    monkeypatch.setattr(writer, "CHUNK_SIZE", chunk_size)
    threaded, plain = _ways(tmp_path, monkeypatch, lambda path: _write(path, events))
    assert threaded == plain
    # and mcap's reader reads it back through its indexes: every message, none twice
    messages = [e for e in events if e[0].startswith("/")]
    got = [(r.topic, r.log_time_ns, r.data) for r in iter_raw(tmp_path / "thread.mcap")]
    assert sorted(got) == sorted(messages)


def test_a_long_run_is_mcaps_byte_for_byte_and_waits_for_no_chunk_but_the_last(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # over three 4 MiB chunks, as a long execute writes them; a tick of several messages at a time
    blob = bytes(range(256)) * 40
    ticks = [
        (k, [(("/scan", "/pose", "/cmd_vel")[j], blob[: (k * 7 + j) % 9000]) for j in range(3)])
        for k in range(2500)
    ]
    handed: list[int] = []
    finalize = chunks.BackgroundChunks.finalize

    def counted(self: chunks.BackgroundChunks) -> None:
        handed.append(len(self.pending))
        finalize(self)

    monkeypatch.setattr(chunks.BackgroundChunks, "finalize", counted)

    def write(path: Path) -> LogWriter:
        with LogWriter(path, metadata={"seed": "1"}) as log:
            for t, tick in ticks:
                log.write_tick(t * 1000, tick)
        return log

    threaded, plain = _ways(tmp_path, monkeypatch, write)
    assert threaded == plain
    # each chunk that filled during the run found the one before still waiting to be written: it
    # was compressed while the run went on. The last, at close, found none: the provenance
    # record written before it had written the one before
    assert len(handed) >= 4 and handed == [0] + [1] * (len(handed) - 2) + [0]


def _failing(monkeypatch: pytest.MonkeyPatch) -> list[threading.Thread]:
    """Compression fails on the thread; returns the threads started, to check they were joined."""
    started: list[threading.Thread] = []

    def compress(data: bytes) -> tuple[bytes, int]:
        started.append(threading.current_thread())
        raise MemoryError("no room to compress")

    monkeypatch.setattr(chunks, "_compress", compress)
    monkeypatch.setattr(writer, "CHUNK_SIZE", 100)
    return started


def test_a_failed_compression_is_raised_on_close_and_leaves_no_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    started = _failing(monkeypatch)
    path = tmp_path / "run.mcap"
    path.write_bytes(b"old")
    with pytest.raises(MemoryError, match="no room"), LogWriter(path, metadata={}) as log:
        log.write_raw("/cmd_vel", 0, b"x" * 200)  # fills a chunk: handed to the thread
        assert log._chunks is not None and len(log._chunks.pending) == 1
    assert started and not any(t.is_alive() for t in started)
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["run.mcap"]


def test_a_failed_compression_is_raised_by_the_next_chunk_that_fills(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    started = _failing(monkeypatch)
    with pytest.raises(MemoryError), LogWriter(tmp_path / "run.mcap", metadata={}) as log:
        log.write_raw("/cmd_vel", 0, b"x" * 200)
        log.write_raw("/cmd_vel", 1, b"x" * 200)  # the second chunk waits for the first
        pytest.fail("the first chunk's error was lost")
    assert len(started) == 1 and not started[0].is_alive()
    assert list(tmp_path.iterdir()) == []


def test_a_run_that_fails_with_a_chunk_on_the_thread_joins_it_and_leaves_no_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(writer, "CHUNK_SIZE", 100)
    release = threading.Event()
    compress = chunks._compress
    threads: list[threading.Thread] = []

    def slow(data: bytes) -> tuple[bytes, int]:
        threads.append(threading.current_thread())
        release.wait(5)
        return compress(data)

    monkeypatch.setattr(chunks, "_compress", slow)
    with (
        pytest.raises(RuntimeError, match="interrupted"),
        LogWriter(tmp_path / "run.mcap", metadata={}) as log,
    ):
        log.write_raw("/cmd_vel", 0, b"x" * 200)
        threading.Timer(0.05, release.set).start()
        raise RuntimeError("interrupted")
    assert threads and not threads[0].is_alive()
    assert list(tmp_path.iterdir()) == []
