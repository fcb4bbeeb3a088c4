"""Robots that speak the Foxglove WebSocket protocol, for ``drive``'s tests and benchmark.

:class:`BridgeSim` is the simulator behind a Foxglove server. In ``cdr`` it is a Foxglove SDK
server that speaks like a ROS 2 ``foxglove_bridge``: it advertises ``/scan``
(``sensor_msgs/msg/LaserScan``, in a ``laser`` frame mounted with a yaw, as on a TurtleBot),
``/odom`` (``nav_msgs/msg/Odometry``), ``/tf`` and ``/tf_static`` (``tf2_msgs/msg/TFMessage``)
with ``ros2msg`` schemas and CDR payloads serialised by ``rosbags``, and accepts a CDR or JSON
``geometry_msgs/msg/Twist`` on ``/cmd_vel``. In ``json`` it is ``lfdfuse teleop``'s own server
(:class:`~lfdfuse.sources.teleop.foxglove_server.FoxgloveLive`), streaming what
``teleop --input foxglove`` streams. ``lockstep`` steps the simulator as soon as a command
answers a scan (faster than real time, same closed loop); otherwise it runs at the robot's
10 Hz. Fault hooks (``cdr``): pause the scans, inject a payload, drop the server and bring it
back on the same port.

:class:`BagReplay` republishes a ROS 2 MCAP bag's CDR messages with their own schemas, paced
by their log times (``speed`` × real time).

Not part of the pipeline: a test rig (``tests/drive``, the ``drive`` benchmark).
"""

from __future__ import annotations

import math
import queue
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import foxglove
import numpy as np
from foxglove import Channel, Context, Schema
from foxglove.websocket import Capability, ChannelView, Client, ClientChannel, ServerListener
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from lfdfuse.log.reader import iter_raw
from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.loop import side_beam_index
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.sources.teleop.foxglove_server import FoxgloveLive
from lfdfuse.sources.teleop.inputs import TwistError, parse_twist
from lfdfuse.world.model import World

_STORE = get_typestore(Stores.ROS2_HUMBLE)
_T = _STORE.types
CDR_TOPICS = {
    "/scan": "sensor_msgs/msg/LaserScan",
    "/odom": "nav_msgs/msg/Odometry",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
}


@dataclass(frozen=True)
class Received:
    """A client command as the robot got it."""

    wall_s: float
    tick: int
    v_mps: float
    omega_rps: float
    encoding: str


class _Listener(ServerListener):
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.channels: dict[tuple[int, int], ClientChannel] = {}
        self.subscribed: set[str] = set()
        self.commands: queue.Queue[tuple[float, float, float, str]] = queue.Queue()
        self.stamps: list[int] = []  # header stamps of TwistStamped commands
        self.bad = 0

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        with self.lock:
            self.subscribed.add(channel.topic)

    def on_client_advertise(self, client: Client, channel: ClientChannel) -> None:
        with self.lock:
            self.channels[(client.id, channel.id)] = channel

    def on_client_unadvertise(self, client: Client, client_channel_id: int) -> None:
        with self.lock:
            self.channels.pop((client.id, client_channel_id), None)

    def on_message_data(self, client: Client, client_channel_id: int, data: bytes) -> None:
        with self.lock:
            ch = self.channels.get((client.id, client_channel_id))
        if ch is None or ch.topic != "/cmd_vel":
            return
        try:
            if ch.encoding == "cdr":
                name = (
                    ch.schema_name if ch.schema_name.endswith("TwistStamped") else "geometry_msgs/msg/Twist"
                )
                m: Any = _STORE.deserialize_cdr(bytes(data), name)
                if name.endswith("TwistStamped"):
                    self.stamps.append(int(m.header.stamp.sec) * 1_000_000_000 + int(m.header.stamp.nanosec))
                    m = m.twist
                v, w = float(m.linear.x), float(m.angular.z)
            else:
                v, w = parse_twist(bytes(data))
        except Exception:  # a test rig counts what it cannot read
            self.bad += 1
            return
        self.commands.put((time.monotonic(), v, w, ch.encoding))


def _stamp(t_ns: int) -> Any:
    return _T["builtin_interfaces/msg/Time"](sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000)


def _header(t_ns: int, frame: str) -> Any:
    return _T["std_msgs/msg/Header"](stamp=_stamp(t_ns), frame_id=frame)


def _quat(theta: float) -> Any:
    return _T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2))


def _vec(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
    return _T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)


def _tf(t_ns: int, parent: str, child: str, x: float, y: float, theta: float) -> Any:
    tr = _T["geometry_msgs/msg/Transform"](translation=_vec(x, y), rotation=_quat(theta))
    return _T["geometry_msgs/msg/TransformStamped"](
        header=_header(t_ns, parent), child_frame_id=child, transform=tr
    )


def cdr_scan(
    t_ns: int, ranges_m: np.ndarray, start_rad: float, inc_rad: float, max_m: float, frame: str
) -> bytes:
    m = _T["sensor_msgs/msg/LaserScan"](
        header=_header(t_ns, frame),
        angle_min=start_rad,
        angle_max=start_rad + inc_rad * (len(ranges_m) - 1),
        angle_increment=inc_rad,
        time_increment=0.0,
        scan_time=0.1,
        range_min=0.05,
        range_max=max_m,
        ranges=np.asarray(ranges_m, dtype=np.float32),
        intensities=np.zeros(0, dtype=np.float32),
    )
    return bytes(_STORE.serialize_cdr(m, "sensor_msgs/msg/LaserScan"))


def cdr_odom(t_ns: int, x: float, y: float, theta: float) -> bytes:
    cov = np.zeros(36)
    pose = _T["geometry_msgs/msg/PoseWithCovariance"](
        pose=_T["geometry_msgs/msg/Pose"](
            position=_T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0), orientation=_quat(theta)
        ),
        covariance=cov,
    )
    twist = _T["geometry_msgs/msg/TwistWithCovariance"](
        twist=_T["geometry_msgs/msg/Twist"](linear=_vec(), angular=_vec()), covariance=cov
    )
    m = _T["nav_msgs/msg/Odometry"](
        header=_header(t_ns, "odom"), child_frame_id="base_link", pose=pose, twist=twist
    )
    return bytes(_STORE.serialize_cdr(m, "nav_msgs/msg/Odometry"))


def cdr_tf(transforms: list[Any]) -> bytes:
    return bytes(
        _STORE.serialize_cdr(_T["tf2_msgs/msg/TFMessage"](transforms=transforms), "tf2_msgs/msg/TFMessage")
    )


@dataclass
class BridgeSim:
    """See the module docstring. Use as a context manager; :meth:`run` in a thread or in the test."""

    world: World
    encoding: str = "cdr"  # cdr | json
    start: Pose | None = None
    lockstep: bool = True
    laser_yaw_rad: float = math.pi / 2  # cdr: the scanner faces the robot's left (a TurtleBot)
    port: int = 0
    seed: int = 0
    command_timeout_s: float = 1.0  # lockstep: how long a scan waits for its command
    #: cdr: the robot's command topic is TwistStamped (ROS 2 Jazzy), advertised as a bridge would
    cmd_stamped: bool = False
    received: list[Received] = field(default_factory=list)
    poses: list[tuple[float, float, float]] = field(default_factory=list)
    sides: list[tuple[float, float]] = field(default_factory=list)  # laser range at +90°, −90°
    scans_paused: threading.Event = field(default_factory=threading.Event)
    stopped: threading.Event = field(default_factory=threading.Event)

    def __post_init__(self) -> None:
        self.sensors = SensorParams()
        self.sim = Simulator(self.world, np.random.default_rng(self.seed), self.sensors)
        self.listener = _Listener()
        self.context = Context()
        self.tick = 0
        self.collisions = 0
        self.live: FoxgloveLive | None = None
        self.channels: dict[str, Channel] = {}
        if self.encoding == "json":  # lfdfuse teleop's own server
            self.live = FoxgloveLive(world=self.world, sensors=self.sensors, port=self.port)
            self.port = self.live.port
            return
        self._start_server()
        self.channels = {
            t: Channel(
                t,
                schema=Schema(name=n, encoding="ros2msg", data=_STORE.generate_msgdef(n)[0].encode()),
                message_encoding="cdr",
                context=self.context,
            )
            for t, n in CDR_TOPICS.items()
        }
        if self.cmd_stamped:
            n = "geometry_msgs/msg/TwistStamped"
            self.channels["/cmd_vel"] = Channel(
                "/cmd_vel",
                schema=Schema(name=n, encoding="ros2msg", data=_STORE.generate_msgdef(n)[0].encode()),
                message_encoding="cdr",
                context=self.context,
            )

    def _start_server(self) -> None:
        self.server = foxglove.start_server(
            name="bridge-sim",
            host="127.0.0.1",
            port=self.port,
            capabilities=[Capability.ClientPublish],
            supported_encodings=["cdr", "json"],
            server_listener=self.listener,
            context=self.context,
        )
        self.port = self.server.port

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"

    def drop(self, down_s: float) -> None:
        """The connection drops: the server goes away for ``down_s`` and returns on the same port."""
        assert self.live is None, "cdr only"
        self.server.stop()
        time.sleep(down_s)
        for _ in range(50):
            try:
                self._start_server()
                return
            except RuntimeError:
                time.sleep(0.05)
        raise RuntimeError("could not restart the server")

    def inject(self, topic: str, payload: bytes) -> None:
        assert self.live is None, "cdr only"
        self.channels[topic].log(payload, log_time=self.tick * self.sim.dt_ns)

    def publish(self, obs: Observation) -> None:
        t, p, r = obs.t_ns, obs.pose, obs.reading
        geom = self.sensors.laser.geometry
        if self.live is not None:
            if self.scans_paused.is_set():
                raise NotImplementedError("json: teleop's server streams every scan")
            self.live.record(obs, (0.0, 0.0))
            return
        self.channels["/odom"].log(cdr_odom(t, p.x, p.y, p.theta), log_time=t)
        tfs = [_tf(t, "odom", "base_link", p.x, p.y, p.theta)]
        self.channels["/tf"].log(cdr_tf(tfs), log_time=t)
        if obs.k % 10 == 0:
            laser = _tf(t, "base_link", "laser", 0.1, 0.0, self.laser_yaw_rad)
            self.channels["/tf_static"].log(cdr_tf([laser]), log_time=t)
        if not self.scans_paused.is_set():
            start = geom.start_rad - self.laser_yaw_rad
            scan = cdr_scan(t, r.ranges_m, start, geom.increment_rad, geom.max_range_m, "laser")
            self.channels["/scan"].log(scan, log_time=t)

    def wait_for_subscriber(self, timeout_s: float = 10.0, *, publisher: bool = True) -> bool:
        """Wait until a client subscribed to ``/scan`` (and, with ``publisher``, advertised a channel)."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            if self.live is not None:
                if self.live.subscribed("/scan") and (self.live.client_channels or not publisher):
                    return True
            else:
                with self.listener.lock:
                    if "/scan" in self.listener.subscribed and (self.listener.channels or not publisher):
                        return True
            time.sleep(0.01)
        return False

    def _take(self, timeout_s: float) -> list[tuple[float, float, float, str]]:
        if self.live is not None:
            return self._take_live(self.live, timeout_s)
        got = []
        try:
            got.append(self.listener.commands.get(timeout=timeout_s))
            while True:
                got.append(self.listener.commands.get_nowait())
        except queue.Empty:
            pass
        return got

    def _take_live(self, live: FoxgloveLive, timeout_s: float) -> list[tuple[float, float, float, str]]:
        """The commands teleop's server queued (it is polled, as teleop polls it each period)."""
        end = time.monotonic() + timeout_s
        while True:
            got = []
            for inp in live.poll(0.0):
                try:
                    got.append((time.monotonic(), *parse_twist(inp.text.encode()), "json"))
                except TwistError:
                    self.listener.bad += 1
            if got or time.monotonic() >= end:
                return got
            time.sleep(0.0005)

    def run(self, seconds: float) -> None:
        """Simulate ``seconds`` of robot time (or until :attr:`stopped` is set)."""
        dt = self.sim.robot.dt_s
        obs = self.sim.reset(self.start)
        cmd = (0.0, 0.0)
        t_next = time.monotonic()
        angles = self.sensors.laser.geometry.angles
        i_left, i_right = side_beam_index(angles, math.pi / 2), side_beam_index(angles, -math.pi / 2)
        for _ in range(int(round(seconds / dt))):
            if self.stopped.is_set():
                break
            self.poses.append(obs.pose.as_tuple())
            self.sides.append((float(obs.reading.ranges_m[i_left]), float(obs.reading.ranges_m[i_right])))
            self.publish(obs)
            if self.lockstep and not self.scans_paused.is_set():
                got = self._take(self.command_timeout_s)
            else:
                t_next += dt
                got = self._take(max(0.0, t_next - time.monotonic()))
                time.sleep(max(0.0, t_next - time.monotonic()))
            for wall, v, w, enc in got:
                self.received.append(Received(wall, self.tick, v, w, enc))
                cmd = (v, w)
            obs = self.sim.step(*cmd)
            self.tick += 1
        self.collisions = self.sim.collisions

    def close(self) -> None:
        self.stopped.set()
        if self.live is not None:
            self.live.close()
            return
        for ch in self.channels.values():
            ch.close()
        self.server.stop()

    def __enter__(self) -> BridgeSim:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class BagReplay:
    """Republishes a ROS 2 MCAP bag (CDR, ``ros2msg`` schemas) as ``foxglove_bridge`` would."""

    def __init__(self, path: str | Path, *, speed: float = 1.0, port: int = 0) -> None:
        self.path = Path(path)
        self.speed = speed
        self.listener = _Listener()
        self.context = Context()
        self.server = foxglove.start_server(
            name="bag-replay",
            host="127.0.0.1",
            port=port,
            capabilities=[Capability.ClientPublish],
            supported_encodings=["cdr"],
            server_listener=self.listener,
            context=self.context,
        )
        self.channels: dict[str, Channel] = {}
        self.messages: list[tuple[int, str, bytes]] = []  # (log time, topic, data)
        static: list[tuple[str, bytes]] = []
        for raw in iter_raw(self.path):
            if raw.topic not in ("/scan", "/odom", "/tf", "/tf_static", "/cmd_vel"):
                continue
            if raw.topic not in self.channels:
                get_types_from_msg(
                    raw.schema_data.decode(), raw.schema_name
                )  # the bag's own definitions parse
                self.channels[raw.topic] = Channel(
                    raw.topic,
                    schema=Schema(name=raw.schema_name, encoding=raw.schema_encoding, data=raw.schema_data),
                    message_encoding=raw.message_encoding,
                    context=self.context,
                )
            if raw.topic == "/tf_static":
                static.append((raw.topic, raw.data))
            self.messages.append((raw.log_time_ns, raw.topic, raw.data))
        self.static = static

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.server.port}"

    def wait_for_subscriber(self, timeout_s: float = 10.0) -> bool:
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            with self.listener.lock:
                if "/scan" in self.listener.subscribed:
                    return True
            time.sleep(0.01)
        return False

    def run(self) -> int:
        """Replay every message in time order; returns how many were published."""
        if not self.messages:
            return 0
        t0, wall0 = self.messages[0][0], time.monotonic()
        next_static = 0
        for t, topic, data in self.messages:
            due = wall0 + (t - t0) / 1e9 / self.speed
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            if t >= next_static:  # latched transforms, repeated for a late subscriber
                for stopic, sdata in self.static:
                    self.channels[stopic].log(sdata, log_time=t)
                next_static = t + 1_000_000_000
            self.channels[topic].log(data, log_time=t)
        return len(self.messages)

    def close(self) -> None:
        for ch in self.channels.values():
            ch.close()
        self.server.stop()

    def __enter__(self) -> BagReplay:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def main() -> None:
    """Serve a simulated robot over the Foxglove protocol in real time (the drive benchmark's robot)."""
    import argparse

    from lfdfuse.world.model import load_world

    ap = argparse.ArgumentParser(description=main.__doc__)
    ap.add_argument("--world", default="tee")
    ap.add_argument("--encoding", choices=("cdr", "json"), default="cdr")
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--port", type=int, default=0)
    args = ap.parse_args()
    with BridgeSim(load_world(args.world), encoding=args.encoding, lockstep=False, port=args.port) as robot:
        sys.stdout.write(f"{robot.url}\n")
        sys.stdout.flush()
        if robot.wait_for_subscriber(60.0):
            robot.run(args.seconds)


if __name__ == "__main__":
    main()
