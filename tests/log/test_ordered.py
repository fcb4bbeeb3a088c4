"""Reading in log-time order chunk by chunk gives exactly mcap's own order, on any file."""

from __future__ import annotations

import io

from hypothesis import given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from lfdfuse.log.ordered import _sequential_chunks, in_log_time_order

TOPICS = ("/scan", "/odom", "/cmd_vel")


def _file(times: list[int], topics: list[int], chunk_size: int, compressed: bool) -> bytes:
    buf = io.BytesIO()
    w = Writer(
        buf, chunk_size=chunk_size, compression=CompressionType.ZSTD if compressed else CompressionType.NONE
    )
    w.start()
    schema = w.register_schema("s", "jsonschema", b"{}")
    ids = [w.register_channel(t, "json", schema) for t in TOPICS]
    for i, (t, k) in enumerate(zip(times, topics, strict=True)):
        w.add_message(ids[k], log_time=t, publish_time=t + 1, data=f"{i}".encode(), sequence=i)
    w.finish()
    return buf.getvalue()


def _mcap(data: bytes, topics: list[str] | None) -> list[tuple[str, int, int, bytes]]:
    r = make_reader(io.BytesIO(data))
    return [
        (c.topic, m.log_time, m.publish_time, m.data)
        for _s, c, m in r.iter_messages(topics=topics, log_time_order=True)
    ]


def _ours(data: bytes, topics: list[str] | None) -> list[tuple[str, int, int, bytes]]:
    f = io.BytesIO(data)
    return [(c.topic, t, p, d) for _s, c, t, p, d in in_log_time_order(make_reader(f), f, topics)]


@settings(max_examples=150)
@given(
    st.lists(st.tuples(st.integers(0, 40), st.integers(0, 2)), max_size=120),
    st.sampled_from(["sorted", "as drawn"]),
    st.integers(30, 600),
    st.booleans(),
    st.sampled_from([None, ["/scan"], ["/odom", "/cmd_vel"]]),
)
def test_same_order_as_mcap(
    msgs: list[tuple[int, int]], order: str, chunk_size: int, compressed: bool, topics: list[str] | None
) -> None:
    if order == "sorted":
        msgs = sorted(msgs, key=lambda m: m[0])
    data = _file([t for t, _ in msgs], [k for _, k in msgs], chunk_size, compressed)
    assert _ours(data, topics) == _mcap(data, topics)


def test_a_file_in_time_order_is_read_chunk_by_chunk() -> None:
    data = _file(list(range(0, 2000, 2)), [i % 3 for i in range(1000)], 400, True)
    r = make_reader(io.BytesIO(data))
    chunks = _sequential_chunks(r, None)
    assert chunks is not None and len(chunks) > 10  # the fast path, over many chunks
    assert _ours(data, None) == _mcap(data, None)
    # a file written out of order overlaps its chunks: mcap's own reader orders it
    shuffled = _file([(i * 7919) % 1000 for i in range(1000)], [0] * 1000, 400, True)
    assert _sequential_chunks(make_reader(io.BytesIO(shuffled)), None) is None
    assert _ours(shuffled, None) == _mcap(shuffled, None)
