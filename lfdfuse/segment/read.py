"""Reading a segmented log back: the ``/lfd/*`` channels into arrays for estimation and evaluation."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import orjson

from lfdfuse.errors import LogError
from lfdfuse.log import lfd
from lfdfuse.log.messages import PROVENANCE
from lfdfuse.log.reader import file_info, iter_messages
from lfdfuse.segment.goals import GoalSegment, Segmentation


@dataclass(frozen=True)
class SegmentedRun:
    """A segmented log loaded for estimation."""

    names: tuple[str, ...]
    t_ns: np.ndarray
    vectors: np.ndarray  # (N, K, 2)
    applicable: np.ndarray  # (N, K)
    goal_met: np.ndarray  # (N, K)
    demo: np.ndarray  # (N, 2)
    informative: np.ndarray  # (N,)
    bac: np.ndarray  # (N,)
    segment_of: np.ndarray  # (N,)
    segments: tuple[GoalSegment, ...]
    metadata: dict[str, str]


def read_segmented(path: str | Path) -> SegmentedRun:
    """Load the ``/lfd/*`` channels of a segmented log; a clear error if there are none or they are broken."""
    info = file_info(path)
    if "/lfd/behaviors" not in info.channels:
        raise LogError(f"{path} is not segmented (no /lfd/behaviors): run `lfdfuse segment {path}` first")
    t_ns: list[int] = []
    rows: list[lfd.BehaviorRow] = []
    demo: list[tuple[float, float, bool]] = []
    bac: list[int] = []
    seg: list[tuple[int, str | None]] = []
    try:
        for topic, _s, t, data in iter_messages(path, topics=list(lfd.SEGMENT_TOPICS)):
            msg: Any = orjson.loads(data)
            if topic == "/lfd/behaviors":
                t_ns.append(t)
                rows.append(lfd.decode_behaviors(msg))
            elif topic == "/lfd/demo":
                demo.append(lfd.decode_demo(msg))
            elif topic == "/lfd/bac":
                bac.append(lfd.decode_bac(msg))
            elif topic == "/lfd/segment":
                seg.append(lfd.decode_segment(msg))
    except (orjson.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
        raise LogError(
            f"{path}: broken /lfd/* messages ({exc.__class__.__name__}); segment the demo again"
        ) from exc
    n = len(rows)
    if n == 0 or not (len(demo) == len(bac) == len(seg) == n):
        raise LogError(f"{path}: the /lfd/* channels are incomplete; segment the demo again")
    names = rows[0].names
    if any(r.names != names for r in rows):
        raise LogError(f"{path}: /lfd/behaviors changes its behaviour set; segment the demo again")
    seg_of = np.array([s[0] for s in seg], dtype=np.int64)
    segs: list[GoalSegment] = []
    for idx in np.unique(seg_of):
        where = np.nonzero(seg_of == idx)[0]
        if where[-1] - where[0] + 1 != len(where):
            raise LogError(f"{path}: goal segment {idx} is not contiguous; segment the demo again")
        segs.append(GoalSegment(int(idx), int(where[0]), int(where[-1]) + 1, seg[int(where[0])][1]))
    return SegmentedRun(
        names=names,
        t_ns=np.array(t_ns, dtype=np.int64),
        vectors=np.stack([r.vectors for r in rows]),
        applicable=np.stack([r.applicable for r in rows]),
        goal_met=np.stack([r.goal_met for r in rows]),
        demo=np.array([(x, y) for x, y, _ in demo], dtype=np.float64).reshape(n, 2),
        informative=np.array([ok for _, _, ok in demo], dtype=bool),
        bac=np.array(bac, dtype=np.int64),
        segment_of=seg_of,
        segments=tuple(segs),
        metadata=info.metadata.get(PROVENANCE, {}),
    )


def segmentation_of(seg: SegmentedRun) -> Segmentation:
    return Segmentation(seg.segments, seg.segment_of, seg.bac)
