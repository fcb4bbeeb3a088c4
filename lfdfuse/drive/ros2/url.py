"""The DDS domain of a ROS 2 run and how a run names it (``ros2://domain/N``), without ``cyclonedds``.

The CLI and the session pick the transport by this URL; only the transport itself imports DDS.
"""

from __future__ import annotations

import os

from lfdfuse.drive.options import DriveError

SCHEME = "ros2"
#: the DDS domain ids ROS 2 allows (the port mapping's range)
MAX_DOMAIN = 232


def domain_id(domain: int | None) -> int:
    """``--domain``, else ``ROS_DOMAIN_ID``, else 0; a :class:`DriveError` outside 0–232.

    >>> domain_id(7)
    7
    """
    if domain is None:
        env = os.environ.get("ROS_DOMAIN_ID", "").strip()
        try:
            domain = int(env) if env else 0
        except ValueError:
            raise DriveError(f"ROS_DOMAIN_ID must be a number, got {env!r}") from None
    if not 0 <= domain <= MAX_DOMAIN:
        raise DriveError(f"the DDS domain must be 0–{MAX_DOMAIN}, got {domain}")
    return domain


def ros2_url(domain: int) -> str:
    """The URL of a domain.

    >>> ros2_url(3)
    'ros2://domain/3'
    """
    return f"{SCHEME}://domain/{domain}"


def parse_ros2_url(url: str) -> int:
    """The domain of a ``ros2://domain/N`` URL (:class:`DriveError` otherwise).

    >>> parse_ros2_url("ros2://domain/42")
    42
    """
    head, _, tail = url.partition("://domain/")
    if head != SCHEME or not tail.isdigit():
        raise DriveError(f"not a ROS 2 domain URL: {url!r} (ros2://domain/N)")
    return domain_id(int(tail))
