"""ROS 1 bags (``.bag``, format 2.0); message definitions are always embedded in them.

The reading itself is shared with ROS 2 in :mod:`.rosbag`.
"""

from __future__ import annotations

from pathlib import Path

from lfdfuse.sources.importers.records import TopicChoice
from lfdfuse.sources.importers.rosbag import BagSource, is_rosbag1

NAME = "ros1"


def detect(path: Path) -> bool:
    """A file that starts with the ROS 1 bag header."""
    return is_rosbag1(path)


def bag_path(path: Path) -> Path:
    """What rosbags reads: the bag itself, whatever it is named (:class:`.rosbag.BagReader` is
    told the generation, it does not guess it from the ``.bag`` suffix)."""
    return path


def open_source(path: Path, *, topics: TopicChoice) -> BagSource:
    return BagSource(bag_path(path), fmt=NAME, topics=topics, ros2=False)
