"""ROS 2 bags: MCAP files with cdr messages, rosbag2 folders (``metadata.yaml``) and bare ``.db3``.

Bags without embedded message definitions (rosbag2 sqlite before Iron) are read with the
standard ROS 2 type store. The reading itself is shared with ROS 1 in :mod:`.rosbag`.
"""

from __future__ import annotations

from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader

from lfdfuse.sources.importers.records import TopicChoice
from lfdfuse.sources.importers.rosbag import BagSource

NAME = "ros2"
_SQLITE_MAGIC = b"SQLite format 3\x00"
_MCAP_MAGIC = b"\x89MCAP0\r\n"


def _mcap_encodings(path: Path) -> set[str]:
    try:
        with path.open("rb") as f:
            summary = make_reader(f).get_summary()
    except (McapError, OSError, ValueError, EOFError, AssertionError):
        return set()
    return set() if summary is None else {c.message_encoding for c in summary.channels.values()}


def detect(path: Path) -> bool:
    """A rosbag2 folder, a ``.db3`` file, or an MCAP file whose messages are cdr."""
    if path.is_dir():
        return (path / "metadata.yaml").is_file() or any(path.glob("*.db3")) or any(path.glob("*.mcap"))
    if not path.is_file():
        return False
    with path.open("rb") as f:
        head = f.read(16)
    if head.startswith(_SQLITE_MAGIC):
        return path.suffix == ".db3"
    return head.startswith(_MCAP_MAGIC) and "cdr" in _mcap_encodings(path)


def bag_path(path: Path) -> Path:
    """What rosbags reads: the folder, or a folder's one storage file when it has no metadata."""
    if path.is_dir() and not (path / "metadata.yaml").is_file():
        files = sorted([*path.glob("*.db3"), *path.glob("*.mcap")])
        if len(files) == 1:
            return files[0]
    return path


def open_source(path: Path, *, topics: TopicChoice) -> BagSource:
    return BagSource(bag_path(path), fmt=NAME, topics=topics, ros2=True)
