"""``lfdfuse drive``'s entry: the transport of the ``--connect`` URL, then the run.

:func:`drive` picks the transport by the URL's scheme (:data:`TRANSPORTS`: ``ws://`` and
``wss://`` are the Foxglove WebSocket protocol — ``foxglove_bridge`` on a robot, or
``lfdfuse teleop --input foxglove``; ``ros2://domain/N`` is ROS 2 over DDS, ``--ros2``) and hands
it to :func:`~lfdfuse.drive.lifecycle.run_live`. A new transport is a module with a
:class:`~lfdfuse.drive.transport.Transport` and a line here. The DDS transport is imported only
when asked: ``cyclonedds`` stays off every other path (``lfdfuse --help`` among them).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from lfdfuse.drive.foxglove.client import FoxgloveTransport
from lfdfuse.drive.lifecycle import run_live
from lfdfuse.drive.options import DriveError, DriveOptions, DriveSummary, Notify, Stopper
from lfdfuse.drive.ros2.url import SCHEME as ROS2
from lfdfuse.drive.ros2.url import parse_ros2_url
from lfdfuse.drive.transport import Topics, Transport


def _ros2(url: str, topics: Topics) -> Transport:
    """The DDS transport (``cyclonedds`` is loaded here, on the ``--ros2`` path only)."""
    from lfdfuse.drive.ros2.client import Ros2Transport

    return Ros2Transport(parse_ros2_url(url), topics)


#: the transport of each ``--connect`` URL scheme
TRANSPORTS: dict[str, Callable[[str, Topics], Transport]] = {
    "ws": FoxgloveTransport,
    "wss": FoxgloveTransport,
    ROS2: _ros2,
}


def transport_for(opts: DriveOptions) -> Transport:
    """The transport of ``opts.url``'s scheme, asked for ``opts``' topics."""
    scheme, sep, _ = opts.url.partition("://")
    make = TRANSPORTS.get(scheme) if sep else None
    if make is None:
        raise DriveError(f"--connect must be a ws://HOST:PORT URL (or use --ros2), got {opts.url!r}")
    return make(opts.url, Topics(opts.scan_topic, opts.odom_topic, opts.cmd_topic, opts.shadow))


def drive(
    opts: DriveOptions,
    *,
    out: str | Path | None = None,
    notify: Notify = lambda _: None,
    stopper: Stopper | None = None,
) -> DriveSummary:
    """Run the table live against ``opts.url``; record ``out`` (see :mod:`lfdfuse.drive.lifecycle`)."""
    return run_live(opts, transport_for(opts), out=out, notify=notify, stopper=stopper)
