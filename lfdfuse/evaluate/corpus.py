"""A corpus of logs (``lfdfuse evaluate DIR…``): finding them, and comparing fused with each rival.

:func:`find_logs` walks a folder for every log ``lfdfuse import`` reads: a rosbag2 bag is a
folder holding ``metadata.yaml`` beside its ``.db3``/``.mcap`` storage, whatever the folder is
called (``bags/test_drive.bag/`` is one), and is not walked into; any other file is a log when an
importer detects it (a ROS 1 ``.bag``, a ROS 2 ``.mcap`` or ``.db3``, a CARMEN or BreezySLAM
log). lfdfuse's own MCAP files are not robot logs and are left out: give them by name.

:func:`compare` is the summary across logs: fused against one rival, per log the difference of
their scores; how many logs fused is better on, the median difference, and a 95 % interval of
that median by bootstrap over the logs (seeded: the same logs and seed give the same interval).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.errors import LogError
from lfdfuse.sources.importers import robot_format

#: bootstrap resamples of the logs for the interval of a median difference
RESAMPLES = 10_000


def is_rosbag2_folder(path: Path) -> bool:
    """A folder holding a rosbag2 bag: ``metadata.yaml`` and its storage files."""
    return (
        path.is_dir()
        and (path / "metadata.yaml").is_file()
        and (any(path.glob("*.db3")) or any(path.glob("*.mcap")))
    )


def find_logs(folder: Path) -> list[Path]:
    """Every robot log under ``folder`` (see the module docstring), in sorted path order; hidden
    files and folders are skipped."""
    if not folder.is_dir():
        raise LogError(f"no such folder: {folder}")
    if is_rosbag2_folder(folder):
        return [folder]
    found: list[Path] = []
    for root, dirs, files in os.walk(folder):
        here = Path(root)
        dirs.sort()
        keep = []
        for d in dirs:
            if d.startswith("."):
                continue
            if is_rosbag2_folder(here / d):
                found.append(here / d)
            else:
                keep.append(d)
        dirs[:] = keep
        found += [here / f for f in sorted(files) if not f.startswith(".") and robot_format(here / f)]
    return sorted(found)


def expand_logs(paths: Sequence[Path]) -> tuple[list[Path], bool]:
    """The logs ``paths`` name: a file or a rosbag2 folder as it is, any other folder as the logs
    under it. Also whether a folder was walked (then the logs are a corpus, shown as rows)."""
    out: list[Path] = []
    walked = False
    for p in paths:
        if p.is_dir() and not is_rosbag2_folder(p):
            logs = find_logs(p)
            if not logs:
                raise LogError(f"{p}: no log lfdfuse can import under this folder")
            out += logs
            walked = True
        else:
            out.append(p)
    return out, walked


def compare(
    fused: Sequence[float | None],
    other: Sequence[float | None],
    *,
    seed: int,
    higher_is_better: bool = False,
    resamples: int = RESAMPLES,
) -> dict[str, Any]:
    """Fused against one rival over the logs where both have a score.

    ``diff`` is ``fused − other`` per log (an error: negative is fused better; with
    ``higher_is_better``, an accuracy: positive is). Returns ``better`` (logs fused is strictly
    better on), ``ties``, ``of`` (logs compared), ``median_diff`` and ``ci95`` (percentile
    bootstrap of the median over the logs; None without a log).
    """
    pairs = [
        (f, o)
        for f, o in zip(fused, other, strict=True)
        if f is not None and o is not None and math.isfinite(f) and math.isfinite(o)
    ]
    d = np.array([f - o for f, o in pairs], dtype=np.float64)
    n = len(d)
    better = int((d > 0).sum() if higher_is_better else (d < 0).sum())
    out: dict[str, Any] = {"better": better, "ties": int((d == 0).sum()), "of": n}
    if n == 0:
        return out | {"median_diff": None, "ci95": None}
    rng = np.random.default_rng(seed)
    boots = np.median(d[rng.integers(0, n, (resamples, n))], axis=1)
    lo, hi = np.percentile(boots, [2.5, 97.5])
    return out | {
        "median_diff": round(float(np.median(d)), 4),
        "ci95": [round(float(lo), 4), round(float(hi), 4)],
    }
