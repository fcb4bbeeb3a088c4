"""Reading a segmented log back: the ``/lfd/*`` channels into arrays for estimation and evaluation."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import orjson

from lfdfuse.behaviors.primitives import ATTRACT, BASE_BEHAVIORS
from lfdfuse.errors import LogError
from lfdfuse.log import lfd
from lfdfuse.log.messages import PROVENANCE
from lfdfuse.log.reader import file_info, iter_messages
from lfdfuse.segment.demo import TARGET_NAME
from lfdfuse.segment.goals import GoalSegment, Segmentation

#: most behaviours of a segmented log (a BAC is an int64 bit mask)
MAX_BEHAVIORS = 62


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


def _is_behavior(name: object) -> bool:
    if not isinstance(name, str):
        return False
    if name.startswith(ATTRACT):
        return TARGET_NAME.fullmatch(name[len(ATTRACT) :]) is not None
    return name in BASE_BEHAVIORS


class _Columns:
    """The per-step arrays of a segmented log, filled one message at a time (no per-step objects)."""

    def __init__(self, names: tuple[str, ...], capacity: int) -> None:
        self.names = names
        k, n = len(names), max(capacity, 16)
        self.bits = np.left_shift(np.int64(1), np.arange(k, dtype=np.int64))
        self.t_ns = np.empty(n, dtype=np.int64)
        self.vectors = np.empty((n, k, 2))
        self.applicable = np.empty((n, k), dtype=bool)
        self.goal_met = np.empty((n, k), dtype=bool)
        self.n = 0

    def append(self, t_ns: int, rows: list[Any]) -> None:
        if self.n == len(self.t_ns):
            for name in ("t_ns", "vectors", "applicable", "goal_met"):
                old = getattr(self, name)
                new = np.empty((2 * len(old), *old.shape[1:]), dtype=old.dtype)
                new[: self.n] = old[: self.n]
                setattr(self, name, new)
        i = self.n
        self.t_ns[i] = t_ns
        for j, b in enumerate(rows):
            x, y, app, goal = b["x"], b["y"], b["applicable"], b["goal_met"]
            if not (isinstance(app, bool) and isinstance(goal, bool)):
                raise TypeError("applicable and goal_met must be true or false")
            self.vectors[i, j] = (float(x), float(y))
            self.applicable[i, j], self.goal_met[i, j] = app, goal
        if not np.isfinite(self.vectors[i]).all():
            raise ValueError("a behaviour vector is not finite")
        self.n += 1


def read_segmented(path: str | Path) -> SegmentedRun:
    """Load the ``/lfd/*`` channels of a segmented log; a clear error if there are none or they are broken.

    One pass; memory is the per-step arrays (``N × K``), nothing per message.
    """
    info = file_info(path)
    if "/lfd/behaviors" not in info.channels:
        raise LogError(f"{path} is not segmented (no /lfd/behaviors): run `lfdfuse segment {path}` first")
    capacity = info.channels["/lfd/behaviors"][2]
    cols: _Columns | None = None
    demo: list[tuple[float, float]] = []
    informative: list[bool] = []
    bac: list[int] = []
    seg: list[tuple[int, str | None]] = []
    broken = f"{path}: broken /lfd/* messages"
    try:
        for topic, _s, t, data in iter_messages(path, topics=list(lfd.SEGMENT_TOPICS)):
            msg: Any = orjson.loads(data)
            if not isinstance(msg, dict):
                raise TypeError(f"a {topic} message is not a JSON object")
            if topic == "/lfd/behaviors":
                rows = msg["behaviors"]
                if not isinstance(rows, list):
                    raise TypeError("behaviors is not a list")
                names = tuple(b["name"] for b in rows)
                if cols is None:
                    if not names or len(names) > MAX_BEHAVIORS or len(set(names)) != len(names):
                        raise LogError(
                            f"{broken}: /lfd/behaviors names {len(names)} behaviours or repeats one"
                        )
                    bad = [n for n in names if not _is_behavior(n)]
                    if bad:
                        raise LogError(
                            f"{broken}: unknown behaviour {str(bad[0])[:40]!r}; segment the demo again"
                        )
                    cols = _Columns(names, capacity)
                elif names != cols.names:
                    raise LogError(
                        f"{path}: /lfd/behaviors changes its behaviour set; segment the demo again"
                    )
                cols.append(t, rows)
            elif topic == "/lfd/demo":
                x, y, ok = float(msg["x"]), float(msg["y"]), msg["informative"]
                if not isinstance(ok, bool) or not (math.isfinite(x) and math.isfinite(y)):
                    raise ValueError("/lfd/demo needs a finite x, y and a true/false informative")
                demo.append((x, y))
                informative.append(ok)
            elif topic == "/lfd/bac":
                b = msg["bac"]
                if not isinstance(b, int) or isinstance(b, bool):
                    raise TypeError("bac is not an integer")
                bac.append(b)
            elif topic == "/lfd/segment":
                index, goal = lfd.decode_segment(msg)
                if not isinstance(msg["index"], int) or not 0 <= index < 2**31:
                    raise ValueError("a segment index is not a small non-negative integer")
                if goal is not None and not _is_behavior(goal):
                    raise ValueError("a segment goal is not a behaviour")
                seg.append((index, goal))
    except (orjson.JSONDecodeError, KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
        raise LogError(
            f"{broken} ({exc.__class__.__name__}: {str(exc)[:80]}); segment the demo again"
        ) from exc
    n = 0 if cols is None else cols.n
    if cols is None or n == 0 or not (len(demo) == len(bac) == len(seg) == n):
        raise LogError(f"{path}: the /lfd/* channels are incomplete; segment the demo again")
    bac_arr = np.array(bac, dtype=np.int64)
    applicable = cols.applicable[:n]
    if not np.array_equal(bac_arr, (applicable.astype(np.int64) * cols.bits).sum(axis=1)):
        raise LogError(f"{path}: /lfd/bac disagrees with /lfd/behaviors; segment the demo again")
    seg_of = np.array([s[0] for s in seg], dtype=np.int64)
    segs: list[GoalSegment] = []
    for idx in np.unique(seg_of):
        where = np.nonzero(seg_of == idx)[0]
        if where[-1] - where[0] + 1 != len(where):
            raise LogError(f"{path}: goal segment {idx} is not contiguous; segment the demo again")
        segs.append(GoalSegment(int(idx), int(where[0]), int(where[-1]) + 1, seg[int(where[0])][1]))
    return SegmentedRun(
        names=cols.names,
        t_ns=cols.t_ns[:n].copy(),
        vectors=cols.vectors[:n].copy(),
        applicable=applicable.copy(),
        goal_met=cols.goal_met[:n].copy(),
        demo=np.array(demo, dtype=np.float64).reshape(n, 2),
        informative=np.array(informative, dtype=bool),
        bac=bac_arr,
        segment_of=seg_of,
        segments=tuple(segs),
        metadata=info.metadata.get(PROVENANCE, {}),
    )


def segmentation_of(seg: SegmentedRun) -> Segmentation:
    return Segmentation(seg.segments, seg.segment_of, seg.bac)
