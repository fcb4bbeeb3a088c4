"""The Foxglove WebSocket frames: what we build parses back, what is malformed is refused."""

from __future__ import annotations

import orjson
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lfdfuse.drive.foxglove import wire


@given(st.integers(0, 2**32 - 1), st.integers(0, 2**64 - 1), st.binary(max_size=64))
def test_server_message_round_trip(sub: int, t_ns: int, payload: bytes) -> None:
    ev = wire.parse_frame(wire.server_message(sub, t_ns, payload))
    assert ev == wire.MessageData(sub, t_ns, payload)


def test_client_message_layout() -> None:
    frame = wire.client_message(7, b"xy")
    assert frame[0] == 1 and int.from_bytes(frame[1:5], "little") == 7 and frame[5:] == b"xy"


def test_server_info_and_advertise() -> None:
    info = wire.parse_frame(
        '{"op":"serverInfo","name":"b","capabilities":["clientPublish"],"supportedEncodings":["cdr","json"]}'
    )
    assert info == wire.ServerInfo("b", ("clientPublish",), ("cdr", "json"))
    adv = wire.parse_frame(
        orjson.dumps(
            {
                "op": "advertise",
                "channels": [
                    {
                        "id": 3,
                        "topic": "/scan",
                        "encoding": "cdr",
                        "schemaName": "sensor_msgs/msg/LaserScan",
                        "schemaEncoding": "ros2msg",
                        "schema": "float32 a",
                    },
                    {"id": 4, "topic": "/x", "encoding": "json", "schemaName": "X"},
                ],
            }
        ).decode()
    )
    assert isinstance(adv, list) and [c.topic for c in adv] == ["/scan", "/x"]
    assert adv[0].schema == "float32 a" and adv[1].schema == "" and adv[1].schema_encoding == ""
    assert wire.parse_frame('{"op":"unadvertise","channelIds":[3]}') == wire.Unadvertise((3,))
    assert wire.parse_frame('{"op":"somethingNew"}') is None
    assert wire.parse_frame(b"\x02" + bytes(8)) is None  # a time frame: not ours


def test_our_text_frames_are_protocol_json() -> None:
    sub = orjson.loads(wire.subscribe([(1, 10), (2, 11)]))
    assert sub == {
        "op": "subscribe",
        "subscriptions": [{"id": 1, "channelId": 10}, {"id": 2, "channelId": 11}],
    }
    adv = orjson.loads(
        wire.advertise(channel_id=1, topic="/cmd_vel", encoding="cdr", schema_name="T", schema="s")
    )
    assert adv["channels"][0]["schemaEncoding"] == "ros2msg"
    adv = orjson.loads(
        wire.advertise(channel_id=1, topic="/cmd_vel", encoding="json", schema_name="T", schema="")
    )
    assert "schema" not in adv["channels"][0]


@pytest.mark.parametrize(
    "frame", ["not json", '{"no":"op"}', '{"op":"advertise"}', '{"op":"advertise","channels":[{"id":"x"}]}']
)
def test_malformed_frames_raise_wire_error(frame: str) -> None:
    with pytest.raises(wire.WireError):
        wire.parse_frame(frame)
