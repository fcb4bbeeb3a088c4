"""Importers of real robot logs (DESIGN §11): one module per source format.

Each format module has ``detect(path) -> bool`` and ``open_source(path, topics=…) -> Source``
(see :mod:`.records`); :mod:`.convert` turns any source into an lfdfuse demo MCAP.
"""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

from lfdfuse.errors import LogError
from lfdfuse.log.reader import file_info
from lfdfuse.log.writer import PROVENANCE
from lfdfuse.sources.importers import breezyslam, carmen, ros1, ros2
from lfdfuse.sources.importers.records import Source, SourceError, TopicChoice

#: format name → module, in detection order (the cheap, certain checks first)
MCAP_MAGIC = b"\x89MCAP0\r\n"
FORMATS: dict[str, ModuleType] = {"ros1": ros1, "ros2": ros2, "carmen": carmen, "breezyslam": breezyslam}


def is_lfdfuse_log(path: str | Path) -> bool:
    """True for an MCAP file lfdfuse wrote (its provenance record, JSON ``/scan``)."""
    p = Path(path)
    if not p.is_file():
        return False
    with p.open("rb") as f:
        if f.read(8) != MCAP_MAGIC:
            return False
    try:
        info = file_info(p)
    except LogError:
        return False
    scan = info.channels.get("/scan")
    return PROVENANCE in info.metadata and scan is not None and scan[1] == "json"


def require_lfdfuse_log(path: str | Path) -> None:
    """Raise a one-line :class:`LogError` when ``path`` is a robot log that needs ``lfdfuse import``."""
    p = Path(path)
    if p.exists() and not is_lfdfuse_log(p) and any(mod.detect(p) for mod in FORMATS.values()):
        raise LogError(
            f"{p} is a robot log, not an lfdfuse demo: run `lfdfuse import {p} -o demo.mcap` first"
        )


def robot_format(path: Path) -> str | None:
    """The importer that reads ``path`` (a robot log), None for an lfdfuse demo or anything else."""
    if not path.exists() or is_lfdfuse_log(path):
        return None
    return next((str(name) for name, mod in FORMATS.items() if mod.detect(path)), None)


def detect_format(path: Path) -> str:
    """The format of a robot log, or a one-line :class:`SourceError`."""
    if not path.exists():
        raise SourceError(f"no such file or folder: {path}")
    if is_lfdfuse_log(path):
        raise SourceError(f"{path} is already an lfdfuse demo: nothing to import")
    for name, mod in FORMATS.items():
        if mod.detect(path):
            return str(name)
    raise SourceError(f"{path}: not a log format lfdfuse can import ({', '.join(FORMATS)}; see --format)")


def open_source(path: Path, *, fmt: str | None = None, topics: TopicChoice = TopicChoice()) -> Source:
    """Open a robot log as a :class:`Source` (format detected unless given)."""
    name = fmt or detect_format(path)
    mod = FORMATS.get(name)
    if mod is None:
        raise SourceError(f"unknown format {name!r} (formats: {', '.join(FORMATS)})")
    if not path.exists():
        raise SourceError(f"no such file or folder: {path}")
    src: Source = mod.open_source(path, topics=topics)
    return src


__all__ = [
    "FORMATS",
    "Source",
    "SourceError",
    "TopicChoice",
    "detect_format",
    "is_lfdfuse_log",
    "open_source",
    "robot_format",
]
