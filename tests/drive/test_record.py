"""The live log's own pieces: the DriveCommand codec against its schema, the log clock's laws."""

from __future__ import annotations

import jsonschema
import orjson
from hypothesis import given
from hypothesis import strategies as st

from lfdfuse.drive.record import LogClock
from lfdfuse.log.command import DriveCommand
from lfdfuse.log.schemas import schema


@given(
    st.integers(0, 2**62),
    st.floats(-2, 2),
    st.floats(-3, 3),
    st.sampled_from(["network", "stale", "stop"]),
    st.booleans(),
    st.one_of(st.none(), st.floats(0, 1e3)),
    st.one_of(st.none(), st.floats(0, 180)),
)
def test_drive_command_round_trip_and_schema(
    t: int, v: float, w: float, source: str, sent: bool, lat: float | None, err: float | None
) -> None:
    data = DriveCommand(t, v, w, source, sent, lat, err).encode()
    msg = orjson.loads(data)
    jsonschema.validate(msg, schema(DriveCommand.SCHEMA))
    back = DriveCommand.decode(data)
    assert (back.t_ns, back.source, back.sent) == (t, source, sent)
    assert abs(back.v_mps - v) <= 1e-6 and abs(back.omega_rps - w) <= 1e-6
    assert (back.latency_ms is None) == (lat is None) and (back.heading_error_deg is None) == (err is None)
    assert back.encode() == data


@given(st.lists(st.tuples(st.booleans(), st.integers(-(10**12), 10**12), st.floats(0, 1e4)), max_size=60))
def test_log_times_strictly_increase_whatever_the_stamps(events: list[tuple[bool, int, float]]) -> None:
    clock, last = LogClock(), -1
    for is_scan, stamp, wall in events:
        t = clock.at_scan(stamp, wall) if is_scan else clock.at_wall(wall)
        assert t > last and t >= 0
        last = t


def test_a_watchdog_command_between_scans_sits_by_the_wall_clock() -> None:
    clock = LogClock()
    assert clock.at_scan(5_000_000_000, 100.0) == 5_000_000_000
    assert clock.at_wall(100.3) == 5_300_000_000
    assert clock.at_scan(5_100_000_000, 100.35) == 5_300_000_001  # a scan never goes back in the log
