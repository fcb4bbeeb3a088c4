"""The seam between ``drive``'s run and the protocol that reaches the robot.

A :class:`Transport` opens a :class:`Link` to one robot; the link is an async stream of
:class:`Ready` (once: the scan is subscribed and, outside ``--shadow``, the command channel is
open) and :class:`Arrival` events (a decoded record, its :class:`~lfdfuse.drive.decode.Role`
and when it arrived), and it sends commands. Everything else — signals, ``--duration``,
reconnecting with back-off, the stale-scan watchdog, latency, the recording, the summary —
is the run's (:mod:`lfdfuse.drive.lifecycle`) and the same for every transport.

What is a protocol's own stays inside its transport: how channels are discovered and matched
to roles (topic names, and for a DDS transport the QoS of each role), the encoding of the
command (by the type the robot expects), and how its messages decode (through the registry of
:mod:`lfdfuse.drive.decoders`). A link's failures are :class:`Lost` (the run retries while
``--duration`` lasts); a refusal that no retry can mend is a
:class:`~lfdfuse.drive.options.DriveError`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, Self

from lfdfuse.drive.decode import Record, Role

#: ``warn(key, text)``: a note worth telling once per key (the run counts repeats)
Warn = Callable[[str, str], None]


@dataclass(frozen=True)
class Topics:
    """What the run asks of the robot: its topics, and whether only to listen (``--shadow``)."""

    scan: str = "/scan"
    odom: str = "/odom"
    cmd: str = "/cmd_vel"
    shadow: bool = False


@dataclass(frozen=True)
class Ready:
    """The scan is subscribed (and, outside ``--shadow``, commands can be sent)."""

    camera: bool  # a channel of target detections is subscribed too
    command: str  # the command's encoding and type ('cdr geometry_msgs/msg/Twist'; '' in --shadow)


@dataclass(frozen=True)
class Arrival:
    """One decoded message: what it is to ``drive``, the record, and when it arrived.

    ``arrived_s`` is :func:`time.perf_counter` and ``cpu_s`` :func:`time.thread_time` the
    moment the transport had the message off the wire, before decoding: the scan → command
    latency counts decoding.
    """

    role: Role
    record: Record
    arrived_s: float
    cpu_s: float


Event = Ready | Arrival


class Lost(Exception):
    """The link dropped, or could not be opened (the run retries while its duration lasts)."""


class Link(Protocol):
    """One open connection to a robot (see the module docstring)."""

    def __aiter__(self) -> Self: ...

    async def __anext__(self) -> Event:
        """The next event; raises :class:`Lost`. Cancel-safe: a cancelled call loses nothing."""
        ...

    async def send(self, v_mps: float, omega_rps: float, stamp_ns: int) -> None:
        """Send a velocity command (``stamp_ns``: the robot's clock); raises :class:`Lost`.
        Only after :class:`Ready`, and never in ``--shadow``."""
        ...

    def not_ready(self) -> str:
        """Why :class:`Ready` has not come yet, in the protocol's words (for an error)."""
        ...

    def publishers(self, topic: str) -> tuple[str, ...]:
        """The names of the nodes publishing on ``topic``, where the protocol reports them (else none)."""
        ...

    async def close(self) -> None:
        """Say goodbye and close (never raises)."""
        ...


class Transport(Protocol):
    """Opens links to one robot."""

    url: str

    async def connect(self, *, timeout_s: float, warn: Warn) -> Link:
        """A new link within ``timeout_s``; raises :class:`Lost` (with why) when there is none."""
        ...
