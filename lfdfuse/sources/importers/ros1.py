"""ROS 1 bags (``.bag``, format 2.0); message definitions are always embedded in them.

The reading itself is shared with ROS 2 in :mod:`.rosbag`.
"""

from __future__ import annotations

from pathlib import Path

from lfdfuse.sources.importers.records import SourceError, TopicChoice
from lfdfuse.sources.importers.rosbag import BagSource, is_rosbag1

NAME = "ros1"


def detect(path: Path) -> bool:
    """A file that starts with the ROS 1 bag header."""
    return is_rosbag1(path)


def bag_path(path: Path) -> Path:
    """``path`` when rosbags can read it as a ROS 1 bag, else a one-line :class:`SourceError`."""
    if path.suffix != ".bag":  # rosbags tells the bag generations apart by the suffix
        raise SourceError(f"{path}: a ROS 1 bag must be named *.bag to be read")
    return path


def open_source(path: Path, *, topics: TopicChoice) -> BagSource:
    return BagSource(bag_path(path), fmt=NAME, topics=topics, ros2=False)
