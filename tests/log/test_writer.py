"""The MCAP writer: what goes in comes back out, in log-time order; a failed run leaves no file."""

from __future__ import annotations

import itertools
from pathlib import Path

import mcap.writer
import orjson
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lfdfuse.errors import LogError
from lfdfuse.log import messages as msg
from lfdfuse.log import writer
from lfdfuse.log.reader import file_info, iter_messages, iter_raw
from lfdfuse.log.writer import PROVENANCE, LogWriter

commands = st.lists(
    st.tuples(
        st.integers(0, 2**62),
        st.floats(-2.0, 2.0, allow_nan=False),
        st.floats(-3.0, 3.0, allow_nan=False),
    ),
    max_size=30,
)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(commands, st.dictionaries(st.text("abcxyz_", min_size=1, max_size=6), st.text(max_size=8), max_size=4))
def test_messages_and_metadata_round_trip(
    tmp_path: Path, cmds: list[tuple[int, float, float]], meta: dict[str, str]
) -> None:
    path = tmp_path / "x.mcap"
    with LogWriter(path, metadata=meta) as log:
        for t, v, w in cmds:
            log.write("/cmd_vel", t, msg.twist(t, v, w))
    got = [(t, orjson.loads(data)) for _, _, t, data in iter_messages(path, topics=["/cmd_vel"])]
    # the reader yields in log-time order; the writer kept every message (stable for equal times)
    expected = sorted(((t, msg.twist(t, v, w)) for t, v, w in cmds), key=lambda m: m[0])
    assert [t for t, _ in got] == [t for t, _ in expected]
    assert sorted(orjson.dumps(m) for _, m in got) == sorted(orjson.dumps(m) for _, m in expected)
    info = file_info(path)
    assert info.metadata[PROVENANCE] == dict(sorted(meta.items()))
    if cmds:
        assert info.channels["/cmd_vel"] == (msg.TOPICS["/cmd_vel"], "json", len(cmds))
    assert [p.name for p in tmp_path.iterdir()] == ["x.mcap"]


def test_an_exception_inside_the_block_leaves_no_file_and_keeps_the_old_one(tmp_path: Path) -> None:
    path = tmp_path / "demo.mcap"
    path.write_bytes(b"old")
    with pytest.raises(RuntimeError), LogWriter(path, metadata={}) as log:
        log.write("/cmd_vel", 0, msg.twist(0, 0.1, 0.0))
        raise RuntimeError("interrupted")
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["demo.mcap"]


def test_unknown_topics_and_missing_folders_are_refused(tmp_path: Path) -> None:
    with pytest.raises(LogError, match="does not exist"), LogWriter(tmp_path / "no" / "x.mcap", metadata={}):
        pass
    with pytest.raises(KeyError, match="no schema"), LogWriter(tmp_path / "y.mcap", metadata={}) as log:
        log.write("/nowhere", 0, {})
    assert not (tmp_path / "y.mcap").exists()


def test_copy_keeps_messages_channels_schemas_and_attachments(tmp_path: Path) -> None:
    src, dst = tmp_path / "a.mcap", tmp_path / "b.mcap"
    with LogWriter(src, metadata={"seed": "1"}) as log:
        log.attach("world.yaml", "application/yaml", b"name: w\n")
        for k in range(5):
            log.write("/cmd_vel", k * 100, msg.twist(k * 100, 0.1 * k, 0.0))
            log.write("/pose", k * 100, msg.pose_in_frame(k * 100, k, 0.0, 0.0))
    with LogWriter(dst, metadata={"seed": "1"}) as log:
        for raw in iter_raw(src):
            log.copy(raw)
    assert list(iter_messages(src)) == list(iter_messages(dst))
    assert file_info(dst).channels == file_info(src).channels


@pytest.mark.parametrize("interrupt", [KeyboardInterrupt, SystemExit])
def test_a_writer_interrupted_as_it_opens_leaves_no_temp_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, interrupt: type[BaseException]
) -> None:
    """SIGTERM (raised as an exception) while the MCAP header is written: ``__exit__`` never runs,
    so ``__enter__`` cleans up itself (a hostile-corpus case caught it once in CI)."""

    def start(*_args: object, **_kwargs: object) -> None:
        raise interrupt

    monkeypatch.setattr(mcap.writer.Writer, "start", start)
    with pytest.raises(interrupt), LogWriter(tmp_path / "run.mcap", metadata={}):
        pass
    assert list(tmp_path.iterdir()) == []


def _two_ways(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, messages: list[tuple[str, int, bytes]]
) -> None:
    """The one-step message path (a message at a time, and the messages of one time together,
    as a tick writes them) writes the bytes mcap's public ``add_message`` writes."""
    files = []
    for way in ("one by one", "ticks", "mcap"):
        if way == "mcap":  # mcap's own add_message and chunk finalising
            monkeypatch.setattr(writer._Messages, "of", classmethod(lambda cls, w: None))
            monkeypatch.setattr(writer.BackgroundChunks, "of", classmethod(lambda cls, w: None))
        path = tmp_path / f"{len(files)}.mcap"
        with LogWriter(path, metadata={"seed": "1"}) as log:
            assert (log._messages is not None) == (way != "mcap")
            assert (log._chunks is not None) == (way != "mcap")
            if way == "ticks":
                for t, tick in itertools.groupby(messages, key=lambda m: m[1]):
                    log.write_tick(t, [(topic, data) for topic, _, data in tick])
            else:
                for topic, t, data in messages:
                    log.write_raw(topic, t, data)
        files.append(path.read_bytes())
    assert files[0] == files[2]
    assert files[1] == files[2]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    st.lists(
        st.tuples(
            st.sampled_from(["/cmd_vel", "/scan", "/pose"]),
            st.one_of(st.integers(0, 3), st.integers(0, 2**63 - 1)),  # often a time again, as in a tick
            st.binary(max_size=60),
        ),
        max_size=40,
    )
)
def test_messages_are_written_as_mcap_writes_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, messages: list[tuple[str, int, bytes]]
) -> None:
    with monkeypatch.context() as m:
        _two_ways(tmp_path, m, messages)


def test_messages_across_chunks_are_written_as_mcap_writes_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # more than one 4 MiB chunk, times out of order
    blob = bytes(range(256)) * 40
    messages = [
        ("/scan" if k % 3 else "/pose", (k * 7919) % 5000, blob[: (k * 3) % 10_000]) for k in range(2500)
    ]
    _two_ways(tmp_path, monkeypatch, messages)


def test_ticks_of_messages_at_one_time_across_chunks_are_written_as_mcap_writes_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # several messages a tick at one time, as a run writes them, over more than one chunk; a
    # tick now and then earlier than the last (a copy of a file out of order)
    blob = bytes(range(256)) * 40
    messages = [
        (
            ("/scan", "/pose", "/cmd_vel")[k % 3],
            10_000 + (k // 3) * 1000 - (5000 if k % 97 == 0 else 0),
            blob[: (k * 7) % 9000],
        )
        for k in range(3000)
    ]
    _two_ways(tmp_path, monkeypatch, messages)
