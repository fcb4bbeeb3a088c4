"""The Foxglove server's listener and poll, without a network: only /cmd_vel from advertised client
channels is queued, in order and bounded; the server itself starts on any free port and stops."""

from __future__ import annotations

from dataclasses import dataclass

import orjson
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sources.teleop.foxglove_server import _QUEUE_MAX, CMD_TOPIC, FoxgloveLive, _Listener
from lfdfuse.sources.teleop.inputs import parse_twist
from lfdfuse.sources.teleop.script import twist_payload
from lfdfuse.world.model import load_world


@dataclass(frozen=True)
class _Client:
    id: int


@dataclass(frozen=True)
class _ClientChannel:
    id: int
    topic: str
    encoding: str = "json"
    schema_name: str = "geometry_msgs/Twist"


@dataclass(frozen=True)
class _View:
    id: int
    topic: str


messages = st.lists(
    st.tuples(st.integers(1, 3), st.integers(1, 3), st.binary(max_size=20)),
    max_size=40,
)


@settings(max_examples=40)
@given(messages)
def test_only_advertised_cmd_vel_channels_are_queued_in_order(sent: list[tuple[int, int, bytes]]) -> None:
    lis = _Listener()
    # client c advertises channel 1 on /cmd_vel and channel 2 on another topic; channel 3 never
    for c in (1, 2, 3):
        lis.on_client_advertise(_Client(c), _ClientChannel(1, CMD_TOPIC))
        lis.on_client_advertise(_Client(c), _ClientChannel(2, "/chatter"))
    for client, channel, data in sent:
        lis.on_message_data(_Client(client), channel, data)
    got = []
    while not lis.received.empty():
        r = lis.received.get_nowait()
        got.append((r.client, r.data))
    assert got == [(c, d) for c, ch, d in sent if ch == 1]
    assert lis.dropped == 0


def test_an_unadvertised_channel_is_forgotten_and_a_flood_is_dropped_not_stored() -> None:
    lis = _Listener()
    lis.on_client_advertise(_Client(7), _ClientChannel(1, CMD_TOPIC))
    for _ in range(_QUEUE_MAX + 25):
        lis.on_message_data(_Client(7), 1, b"{}")
    assert lis.received.qsize() == _QUEUE_MAX and lis.dropped == 25
    lis.on_client_unadvertise(_Client(7), 1)
    lis.on_message_data(_Client(7), 1, b"{}")
    assert lis.received.qsize() == _QUEUE_MAX and lis.dropped == 25


def test_subscribing_to_the_world_asks_for_the_scene_again_and_unsubscribing_forgets_the_client() -> None:
    lis = _Listener()
    lis.on_subscribe(_Client(1), _View(10, "/scan"))
    assert not lis.world_wanted.is_set()
    lis.on_subscribe(_Client(1), _View(11, "/world"))
    assert lis.world_wanted.is_set() and lis.subscribers == {1: {10, 11}}
    lis.on_unsubscribe(_Client(1), _View(10, "/scan"))
    lis.on_unsubscribe(_Client(1), _View(11, "/world"))
    assert lis.subscribers == {}


def test_the_server_polls_client_twists_as_inputs_and_stops() -> None:
    with FoxgloveLive(world=load_world("corridor"), sensors=SensorParams(), port=0) as live:
        assert live.port > 0 and live.url == f"ws://127.0.0.1:{live.port}"
        lis = live._listener
        lis.on_client_advertise(_Client(4), _ClientChannel(9, CMD_TOPIC))
        lis.on_message_data(_Client(4), 9, twist_payload(0.25, -0.5).encode())
        assert live.clients == 1
        (inp,) = live.poll(0.0)
        assert parse_twist(inp.text) == (0.25, -0.5)
        assert "foxglove client 4" in inp.source
        assert live.poll(0.1) == []
        assert orjson.loads(inp.text)  # JSON text, as the client sent it
