"""The ROS 2 transport of ``drive``: a DDS participant that reads and writes as a ROS 2 node would.

A :class:`Ros2Link` is one participant in the domain with a best-effort reader per topic
(:mod:`~lfdfuse.drive.ros2.names`: the scan, odometry, ``/tf``, a transient-local ``/tf_static``,
and in ``--shadow`` or ``record`` the robot's own ``--cmd``). Cyclone DDS calls the readers'
listeners on its own threads; they only take the raw samples (the arrival time stamped there) and
hand them to the run's event loop, where they are decoded (:mod:`lfdfuse.robot.idl` structs, then
the same conversions as ``foxglove_bridge``'s CDR), so a malformed sample is one warning and a
decoding cost counts in the latency.

The link is :class:`Ready` once a publisher of the scan is matched; outside ``--shadow`` it then
creates the command writer, of the type the robot's ``--cmd`` subscriber has (``TwistStamped`` or
``Twist``, from discovery), once the robot's subscriber is matched (so the new link's zero Twist
reaches it); scans that came while it got ready are dropped, as late. When the last scan publisher goes away (the robot's process ended)
the link is :class:`Lost` and the run reconnects: a new participant, discovering afresh. A
publisher of one of our topics with another type, or a QoS that cannot match, is one line.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Self

from cyclonedds._clayer import ddspy_take  # the raw take the binding's own take() wraps
from cyclonedds.builtin import (
    BuiltinDataReader,
    BuiltinTopicDcpsParticipant,
    BuiltinTopicDcpsPublication,
    BuiltinTopicDcpsSubscription,
)
from cyclonedds.core import DDSException, Entity, InstanceState, Listener, SampleState, ViewState
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

from lfdfuse.drive.decode import DecodeError, Record, Role, _cdr_odom, _cdr_scan, _cdr_tf, _cdr_twist
from lfdfuse.drive.ros2 import names
from lfdfuse.drive.ros2.names import Wanted
from lfdfuse.drive.ros2.url import ros2_url
from lfdfuse.drive.transport import Arrival, Event, Lost, Ready, Topics, Warn
from lfdfuse.robot import idl
from lfdfuse.robot.ros import frame_name

#: how long a new link waits for the robot's command subscriber to be discovered beside its scan
COMMAND_DISCOVERY_S = 0.3
#: how long the command writer waits for the robot's subscriber it discovered to match
COMMAND_MATCH_S = 1.5

_READ: dict[Role, Callable[[Any], Record]] = {
    Role.SCAN: _cdr_scan,
    Role.ODOM: _cdr_odom,
    Role.TF: _cdr_tf,
    Role.CMD: _cdr_twist,
}


def _take_raw(reader: DataReader[Any] | None) -> list[bytes]:
    """Every new sample of ``reader`` as its serialised bytes (decoded later, one by one); none
    from a reader being deleted (the binding then hands its listener no reader)."""
    if reader is None:
        return []
    got = ddspy_take(reader._ref, SampleState.Any | ViewState.Any | InstanceState.Any, 64)
    if isinstance(got, int):
        return []
    return [bytes(data) for data, info in got if info.valid_data]


def _delete(entity: Entity) -> None:
    """Delete a DDS entity now (the binding deletes on garbage collection; a second call is a no-op)."""
    with contextlib.suppress(DDSException):
        entity.__del__()


@dataclass(frozen=True)
class _Data:
    wanted: Wanted
    payload: bytes
    arrived_s: float


@dataclass(frozen=True)
class _Matched:
    count: int  # publishers of the scan now matched


@dataclass(frozen=True)
class _Note:
    key: str
    text: str


@dataclass(frozen=True)
class _TypeClash:
    wanted: Wanted  # a publisher of this topic has another type


_Item = _Data | _Matched | _Note | _TypeClash


class Ros2Transport:
    """Links to the ROS 2 robots of one DDS domain (``url``: ``ros2://domain/N``)."""

    def __init__(self, domain: int, topics: Topics, *, listen_cmd: bool | None = None) -> None:
        self.domain = domain
        self.url = ros2_url(domain)
        self.topics = topics
        self.listen_cmd = topics.shadow if listen_cmd is None else listen_cmd

    async def connect(self, *, timeout_s: float, warn: Warn) -> Ros2Link:
        try:
            return Ros2Link(self.domain, self.topics, warn, listen_cmd=self.listen_cmd)
        except DDSException as exc:
            raise Lost(f"cannot join DDS domain {self.domain} ({exc})") from None


class Ros2Link:
    """One participant in the domain (see the module docstring)."""

    def __init__(self, domain: int, topics: Topics, warn: Warn, *, listen_cmd: bool) -> None:
        self.domain = domain
        self.topics = topics
        self.warn = warn
        self.loop = asyncio.get_running_loop()
        self.queue: asyncio.Queue[_Item] = asyncio.Queue()
        self.closed = False
        self.ready = False
        self.matched = 0
        self._ready_s = -math.inf  # when the link became ready (perf_counter)
        self.writer: DataWriter[Any] | None = None
        self.command: type[IdlStruct] = idl.Twist
        self.wanted = names.wanted(scan=topics.scan, odom=topics.odom, cmd=topics.cmd, listen_cmd=listen_cmd)
        self.dp = DomainParticipant(domain)
        self._entities: list[Entity] = []
        self._topics: dict[str, Topic[Any]] = {}
        self._seen_types: dict[str, set[str]] = {}  # DDS topic → type names its publishers use
        self._publisher_keys: dict[str, set[str]] = {}  # ROS topic → participant keys of its publishers
        self._expected = {w.dds: w.type_name for w in self.wanted}
        for w in self.wanted:
            self._reader(w)
        self._pubs = BuiltinDataReader(
            self.dp,
            BuiltinTopicDcpsPublication,
            listener=Listener(on_data_available=lambda _: self._publications()),  # type: ignore[no-untyped-call]
        )
        self._subs = BuiltinDataReader(self.dp, BuiltinTopicDcpsSubscription)
        self._parts = BuiltinDataReader(self.dp, BuiltinTopicDcpsParticipant)
        self._entities += [self._pubs, self._subs, self._parts]

    # -- DDS threads → the loop ----------------------------------------------------------------
    def _put(self, item: _Item) -> None:
        if self.closed:
            return
        with contextlib.suppress(RuntimeError):  # the loop closed under a late callback
            self.loop.call_soon_threadsafe(self.queue.put_nowait, item)

    def _topic(self, name: str, struct: type[IdlStruct]) -> Topic[Any]:
        if name not in self._topics:
            self._topics[name] = Topic(self.dp, name, struct)
            self._entities.append(self._topics[name])
        return self._topics[name]

    def _reader(self, w: Wanted) -> None:
        def data(reader: DataReader[Any] | None) -> None:
            if self.closed:
                return
            arrived = time.perf_counter()
            for payload in _take_raw(reader):
                self._put(_Data(w, payload, arrived))

        def incompatible(reader: DataReader[Any], status: Any) -> None:
            policy = int(status.last_policy_id)
            if policy == names.TYPE_POLICY:  # another type: said once discovery names it
                self._put(_TypeClash(w))
                return
            self._put(
                _Note(
                    f"qos {w.topic}",
                    f"{w.topic}: a publisher's QoS cannot match ours ({names.POLICY_NAMES.get(policy, f'policy {policy}')}; "
                    f"we read it {w.qos_text}): its messages are not received",
                )
            )

        listener = Listener(on_data_available=data, on_requested_incompatible_qos=incompatible)  # type: ignore[no-untyped-call]
        if w.role is Role.SCAN:
            listener.set_on_subscription_matched(
                lambda reader, status: self._put(_Matched(int(status.current_count)))
            )
        reader: DataReader[Any] = DataReader(
            self.dp, self._topic(w.dds, w.struct), qos=w.qos, listener=listener
        )
        self._entities.append(reader)

    def _publications(self) -> None:
        """Take what discovery says of publishers: a note on one of our topics with another
        type; their participants, for :meth:`publishers`. (Called from the listener and when asked.)"""
        reader = getattr(self, "_pubs", None)  # (the listener may fire before it is known)
        if reader is None or self.closed:
            return
        with contextlib.suppress(DDSException):
            for ep in reader.take(N=256):
                if not hasattr(ep, "topic_name"):
                    continue
                topic, type_name = str(ep.topic_name), str(ep.type_name)
                self._seen_types.setdefault(topic, set()).add(type_name)
                if not topic.startswith(f"{idl.TOPIC_PREFIX}/"):
                    continue
                ros = f"/{topic[len(idl.TOPIC_PREFIX) + 1 :]}"
                self._publisher_keys.setdefault(ros, set()).add(str(ep.participant_key))
                want = self._expected.get(topic)
                if want is None or type_name == want or _both_twists(want, type_name):
                    continue
                self._put(
                    _Note(
                        f"type {ros}",
                        f"{ros} is published as {idl.ros_type(type_name)}, not {idl.ros_type(want)}: not received",
                    )
                )

    # -- the link -------------------------------------------------------------------------------
    def __aiter__(self) -> Self:
        return self

    async def __anext__(self) -> Event:
        while True:
            item = await self.queue.get()
            if isinstance(item, _Data):
                if item.wanted.role is Role.SCAN and item.arrived_s < self._ready_s:
                    continue  # came while the link was getting ready: commanding from it would be late
                cpu = time.thread_time()
                try:
                    rec = _decode(item.wanted, item.payload)
                except DecodeError as exc:
                    t = item.wanted.topic
                    self.warn(f"decode {t}", f"{t}: {exc}; ignored (further ones counted)")
                    continue
                return Arrival(item.wanted.role, rec, item.arrived_s, cpu)
            if isinstance(item, _Note):
                self.warn(item.key, item.text)
                continue
            if isinstance(item, _TypeClash):
                self._type_clash(item.wanted)
                continue
            self.matched = item.count
            if item.count > 0 and not self.ready:
                return await self._ready()
            if item.count == 0 and self.ready:
                raise Lost(f"no publisher of {self.topics.scan} is left")

    def _type_clash(self, w: Wanted) -> None:
        self._publications()  # names the other type when discovery has it (one line per topic)
        others = sorted(idl.ros_type(t) for t in self._seen_types.get(w.dds, ()) if t != w.type_name)
        kind = f"published as {', '.join(others)}" if others else "published with another type"
        self.warn(f"type {w.topic}", f"{w.topic} is {kind}, not {idl.ros_type(w.type_name)}: not received")

    async def _ready(self) -> Ready:
        self.ready = True
        if self.topics.shadow:
            self._ready_s = time.perf_counter()
            return Ready(camera=False, command="")
        dds = idl.dds_topic(self.topics.cmd)
        end = time.monotonic() + COMMAND_DISCOVERY_S
        subs = self._subscribers(dds)
        while not subs and time.monotonic() < end:
            await asyncio.sleep(0.02)
            subs = self._subscribers(dds)
        self.command = names.command_struct(set(subs.values()))
        qos = names.COMMAND
        self.writer = DataWriter(self.dp, self._topic(dds, self.command), qos=qos)
        self._entities.append(self.writer)
        # the robot's subscriber is matched before the first command (the new link's zero Twist):
        # a volatile writer's sample reaches only the readers it has already matched
        end = time.monotonic() + COMMAND_MATCH_S
        while subs and time.monotonic() < end:
            matched = set(self.writer.get_matched_subscriptions())
            if matched and all(
                h in matched for h, t in self._subscribers(dds).items() if t == self.command.__idl_typename__
            ):
                break
            await asyncio.sleep(0.01)
        self._ready_s = time.perf_counter()
        return Ready(camera=False, command=f"cdr {idl.ros_type(self.command.__idl_typename__)}")

    def _subscribers(self, dds: str) -> dict[int, str]:
        """The live subscribers discovered on the DDS topic ``dds``: instance handle → type name."""
        got: dict[int, str] = {}
        with contextlib.suppress(DDSException):
            for ep in self._subs.read(N=256):
                info = getattr(ep, "sample_info", None)
                if (
                    getattr(ep, "topic_name", None) == dds
                    and str(ep.participant_key) != str(self.dp.guid)
                    and (info is None or info.instance_state == InstanceState.Alive)
                ):
                    got[int(info.instance_handle) if info is not None else id(ep)] = str(ep.type_name)
        return got

    async def send(self, v_mps: float, omega_rps: float, stamp_ns: int) -> None:
        assert self.writer is not None
        tw = idl.Twist(idl.Vector3(v_mps, 0.0, 0.0), idl.Vector3(0.0, 0.0, omega_rps))
        msg: IdlStruct = tw
        if self.command is idl.TwistStamped:
            msg = idl.TwistStamped(idl.Header(idl.stamp(stamp_ns), frame_name("base_link")), tw)
        try:
            self.writer.write(msg)
        except DDSException as exc:
            raise Lost(f"cannot publish on {self.topics.cmd} ({exc})") from None

    def not_ready(self) -> str:
        self._publications()
        scan = idl.dds_topic(self.topics.scan)
        seen = self._seen_types.get(scan)
        if seen:
            kinds = ", ".join(sorted(idl.ros_type(t) for t in seen))
            return f"{self.topics.scan} ({scan}) in DDS domain {self.domain} is published as {kinds}, not sensor_msgs/msg/LaserScan"
        others = sorted(f"/{t[3:]}" for t in self._seen_types if t.startswith(f"{idl.TOPIC_PREFIX}/"))
        return (
            f"no publisher of {self.topics.scan} ({scan}, sensor_msgs/msg/LaserScan) in DDS domain {self.domain} "
            f"(topics seen: {', '.join(others) or 'none'}; check --domain / ROS_DOMAIN_ID and CYCLONEDDS_URI)"
        )

    def publishers(self, topic: str) -> tuple[str, ...]:
        """The entity names of the participants publishing ``topic`` (those that gave one)."""
        self._publications()
        keys = self._publisher_keys.get(topic)
        if not keys or self.closed:
            return ()
        names = set()
        with contextlib.suppress(DDSException):
            for p in self._parts.read(N=256):
                if str(getattr(p, "key", "")) in keys and (name := _entity_name(p)):
                    names.add(name)
        return tuple(sorted(names))

    async def close(self) -> None:
        self.closed = True
        for e in reversed(self._entities):
            _delete(e)
        self._entities.clear()
        self._topics.clear()
        _delete(self.dp)


def _decode(w: Wanted, payload: bytes) -> Record:
    try:
        msg = w.struct.deserialize(payload)
    except Exception as exc:  # a truncated or foreign payload fails anywhere in the binding
        raise DecodeError(f"undecodable {idl.ros_type(w.type_name)} ({exc.__class__.__name__})") from None
    try:
        return _READ[w.role](msg)
    except DecodeError:
        raise
    except (ValueError, TypeError, AttributeError, IndexError) as exc:
        raise DecodeError(f"unusable {idl.ros_type(w.type_name)} ({exc})") from None


def _both_twists(a: str, b: str) -> bool:
    twists = {idl.Twist.__idl_typename__, idl.TwistStamped.__idl_typename__}
    return a in twists and b in twists


def _entity_name(ep: Any) -> str:
    """The name a participant gave itself (its QoS entity name), else ''."""
    qos = getattr(ep, "qos", None)
    if qos is None:
        return ""
    for p in qos:
        if type(p).__name__ == "EntityName":
            return str(p.name)
    return ""
