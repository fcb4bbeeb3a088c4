"""Which of the server's channels ``drive`` listens to, and under which subscription id.

Pure bookkeeping over the ``advertise`` / ``unadvertise`` messages of one connection: the scan
on ``--scan``; odometry on ``--odom``, else the first odometry-like channel (lfdfuse's own server
calls it ``/pose``); every tf channel (``/tf``, ``/tf_static``); a camera's targets; and in
``--shadow`` the robot's own command on ``--cmd``. Channels whose encoding and schema have no
decoder in :mod:`lfdfuse.drive.decoders` are left alone; a schema that does not parse is a warning, not an error.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lfdfuse.drive.decode import DecodeError, Decoder, Role
from lfdfuse.drive.decoders import decoder_for, role_of
from lfdfuse.drive.foxglove.wire import ServerChannel
from lfdfuse.drive.transport import Topics


@dataclass(frozen=True)
class Sub:
    role: Role
    decode: Decoder
    topic: str
    channel: int


@dataclass
class Subscriptions:
    """The channels of one connection and our subscriptions to them."""

    topics: Topics
    channels: dict[int, ServerChannel] = field(default_factory=dict)
    subs: dict[int, Sub] = field(default_factory=dict)
    _next: int = 0

    @property
    def scan(self) -> bool:
        """The scan channel is subscribed."""
        return any(s.role is Role.SCAN for s in self.subs.values())

    @property
    def camera(self) -> bool:
        """A channel of target detections is subscribed (the robot has a camera)."""
        return any(s.role is Role.TARGETS for s in self.subs.values())

    def stamped_cmd(self) -> bool:
        """The robot's command topic is advertised as ``TwistStamped``: send that type too."""
        return any(
            c.topic == self.topics.cmd and c.schema_name.endswith("TwistStamped")
            for c in self.channels.values()
        )

    def advertised_topics(self) -> list[str]:
        return sorted(c.topic for c in self.channels.values())

    def _wanted(self, ch: ServerChannel) -> Role | None:
        role, t = role_of(ch), self.topics
        if role is Role.SCAN:
            return role if ch.topic == t.scan else None
        if role is Role.ODOM:
            named = any(c.topic == t.odom for c in self.channels.values())
            taken = any(s.role is Role.ODOM for s in self.subs.values())
            return role if ch.topic == t.odom or not (named or taken) else None
        if role is Role.TF or role is Role.TARGETS:
            return role
        if role is Role.CMD:
            return role if t.shadow and ch.topic == t.cmd else None
        return None

    def advertised(self, channels: list[ServerChannel]) -> tuple[list[tuple[int, int]], list[str]]:
        """New channels: the ``(subscription id, channel id)`` pairs to subscribe, and warnings."""
        for ch in channels:
            self.channels[ch.id] = ch
        pairs: list[tuple[int, int]] = []
        warnings: list[str] = []
        subscribed = {s.channel for s in self.subs.values()}
        # the named odometry first, so an odometry-like channel never takes its place
        for ch in sorted(channels, key=lambda c: (c.topic != self.topics.odom, c.id)):
            role = self._wanted(ch)
            if role is None or ch.id in subscribed:
                continue
            try:
                decode = decoder_for(ch)
            except DecodeError as exc:
                warnings.append(f"{exc}; not subscribed")
                continue
            self._next += 1
            self.subs[self._next] = Sub(role, decode, ch.topic, ch.id)
            subscribed.add(ch.id)
            pairs.append((self._next, ch.id))
        return pairs, warnings

    def unadvertised(self, ids: tuple[int, ...]) -> None:
        for cid in ids:
            self.channels.pop(cid, None)
        for sid in [s for s, sub in self.subs.items() if sub.channel in ids]:
            del self.subs[sid]
