"""The live Foxglove side of teleop: the official SDK's WebSocket server (DESIGN §10).

The server streams ``/world``, ``/scan``, ``/pose``, ``/tf``, ``/targets`` and the command the
robot is driven by this period (``/cmd_vel``, whoever gave it: a key, a script, a client) with
the same JSON schemas the MCAP uses, as a robot's bridge streams its own ``/cmd_vel`` (so
``lfdfuse drive --shadow`` can watch a person drive it). It advertises ``clientPublish`` with
``json`` encoding, and takes the ``geometry_msgs/Twist`` (or ``geometry_msgs/msg/Twist``)
messages a client — Foxglove's Teleop panel — publishes on ``/cmd_vel``. Client channels are
matched by topic.

The SDK calls the listener on its own threads, and a slow callback stalls that client: the
callbacks only note the channel or put the raw payload on a queue. The control loop drains
the queue once per period (:meth:`FoxgloveLive.poll`) and parses there
(:func:`~lfdfuse.sources.teleop.inputs.parse_twist`).
"""

from __future__ import annotations

import queue
import threading
from dataclasses import dataclass

import foxglove
import orjson
from foxglove import Channel, Context, Schema
from foxglove.websocket import Capability, ChannelView, Client, ClientChannel, ServerListener

from lfdfuse.errors import LfdError
from lfdfuse.log import messages as msg
from lfdfuse.log.schemas import schema_text
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sources.teleop.inputs import Input
from lfdfuse.world.parse import World

CMD_TOPIC = "/cmd_vel"
TWIST_SCHEMAS = ("geometry_msgs/Twist", "geometry_msgs/msg/Twist")
LIVE_TOPICS = ("/world", "/scan", "/pose", "/tf", "/targets", CMD_TOPIC)
_QUEUE_MAX = 1000  # a client flooding /cmd_vel drops messages rather than memory


@dataclass(frozen=True)
class _Received:
    client: int
    topic: str
    encoding: str
    schema: str
    data: bytes


class _Listener(ServerListener):
    """SDK callbacks: record client channels, queue /cmd_vel payloads. Nothing slow here."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.channels: dict[tuple[int, int], ClientChannel] = {}
        self.subscribers: dict[int, set[int]] = {}  # client → subscribed channel ids
        self.received: queue.Queue[_Received] = queue.Queue(maxsize=_QUEUE_MAX)
        self.world_wanted = threading.Event()
        self.dropped = 0

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        with self.lock:
            self.subscribers.setdefault(client.id, set()).add(channel.id)
        if channel.topic == "/world":
            self.world_wanted.set()  # a late subscriber gets the scene again

    def on_unsubscribe(self, client: Client, channel: ChannelView) -> None:
        with self.lock:
            subs = self.subscribers.get(client.id)
            if subs is not None:
                subs.discard(channel.id)
                if not subs:
                    del self.subscribers[client.id]

    def on_client_advertise(self, client: Client, channel: ClientChannel) -> None:
        with self.lock:
            self.channels[(client.id, channel.id)] = channel

    def on_client_unadvertise(self, client: Client, client_channel_id: int) -> None:
        with self.lock:
            self.channels.pop((client.id, client_channel_id), None)

    def on_message_data(self, client: Client, client_channel_id: int, data: bytes) -> None:
        with self.lock:
            ch = self.channels.get((client.id, client_channel_id))
        if ch is None or ch.topic != CMD_TOPIC:
            return
        try:
            self.received.put_nowait(_Received(client.id, ch.topic, ch.encoding, ch.schema_name, bytes(data)))
        except queue.Full:
            self.dropped += 1


class FoxgloveLive:
    """The server, its channels, and the client command queue. Use as a context manager.

    It is an input source (:meth:`poll`) and a sink (:meth:`record`) of the one loop.
    """

    def __init__(
        self, *, world: World, sensors: SensorParams, host: str = "127.0.0.1", port: int = 8765
    ) -> None:
        self.world = world
        self.laser = sensors.laser.geometry
        self.host = host
        self._listener = _Listener()
        self._context = Context()
        try:
            self._server = foxglove.start_server(
                name="lfdfuse teleop",
                host=host,
                port=port,
                capabilities=[Capability.ClientPublish],
                supported_encodings=["json"],
                server_listener=self._listener,
                context=self._context,
            )
        except RuntimeError as exc:
            raise LfdError(f"cannot start the Foxglove server on {host}:{port}: {exc}") from None
        self._channels = {
            topic: Channel(
                topic,
                schema=Schema(
                    name=msg.TOPICS[topic], encoding="jsonschema", data=schema_text(msg.TOPICS[topic])
                ),
                message_encoding="json",
                context=self._context,
            )
            for topic in LIVE_TOPICS
        }
        self._listener.world_wanted.set()
        self.published = 0

    @property
    def port(self) -> int:
        return self._server.port

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def subscribed(self, topic: str) -> bool:
        """Whether a client subscribes to ``topic``."""
        cid = self._channels[topic].id()
        lis = self._listener
        with lis.lock:
            return any(cid in ids for ids in lis.subscribers.values())

    @property
    def client_channels(self) -> int:
        """Channels the clients advertised (to publish commands on)."""
        with self._listener.lock:
            return len(self._listener.channels)

    def app_url(self) -> str:
        return self._server.app_url() or ""

    @property
    def clients(self) -> int:
        """Clients subscribed to a channel or publishing on one."""
        lis = self._listener
        with lis.lock:
            return len(set(lis.subscribers) | {c for c, _ in lis.channels})

    def poll(self, t_s: float) -> list[Input]:
        """Client messages on ``/cmd_vel`` since the last poll, oldest first."""
        out: list[Input] = []
        while True:
            try:
                r = self._listener.received.get_nowait()
            except queue.Empty:
                return out
            text = r.data.decode("utf-8", errors="replace") if r.encoding == "json" else r.data.hex()
            out.append(Input("message", text, f"foxglove client {r.client} ({r.encoding})", r.schema))

    def record(self, obs: Observation, command: tuple[float, float]) -> None:
        """Stream this period's sensing, and the command driving the robot, to every subscribed client."""
        t, pose, reading = obs.t_ns, obs.pose, obs.reading
        if self._listener.world_wanted.is_set():
            self._listener.world_wanted.clear()
            self._log("/world", t, msg.world_scene(t, self.world))
        self._log("/scan", t, msg.laser_scan(t, reading.ranges_m, self.laser))
        self._log("/pose", t, msg.pose_in_frame(t, pose.x, pose.y, pose.theta))
        self._log("/tf", t, msg.frame_transform(t, pose.x, pose.y, pose.theta))
        self._log("/targets", t, msg.target_detections(t, reading.detections))
        self._log(CMD_TOPIC, t, msg.twist(t, command[0], command[1]))

    def _log(self, topic: str, t_ns: int, message: dict[str, object]) -> None:
        self._channels[topic].log(orjson.dumps(message), log_time=t_ns)
        self.published += 1

    def close(self) -> None:
        for ch in self._channels.values():
            ch.close()
        self._server.stop()

    def __enter__(self) -> FoxgloveLive:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
