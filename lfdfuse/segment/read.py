"""Reading a segmented log back: the ``/lfd/*`` channels into arrays for estimation and evaluation,
alone (:func:`read_segmented`) or with the run they were segmented from, in one pass over the
file's messages (:func:`read_segmented_and_run`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lfdfuse.behaviors.primitives import ATTRACT, BASE_BEHAVIORS
from lfdfuse.errors import LogError
from lfdfuse.log import lfd
from lfdfuse.log.codec import MessageError
from lfdfuse.log.messages import PROVENANCE
from lfdfuse.log.reader import (
    RUN_TOPICS,
    FileInfo,
    Run,
    RunBuilder,
    file_info,
    finish_run,
    hold,
    iter_messages,
    iter_records,
    run_builder,
)
from lfdfuse.log.stamps import check_log_time
from lfdfuse.segment.demo import TARGET_NAME
from lfdfuse.segment.goals import GoalSegment, Segmentation
from lfdfuse.sources.importers import require_lfdfuse_log

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

    def append(self, t_ns: int, row: lfd.BehaviorRow) -> None:
        if self.n == len(self.t_ns):
            for name in ("t_ns", "vectors", "applicable", "goal_met"):
                old = getattr(self, name)
                new = np.empty((2 * len(old), *old.shape[1:]), dtype=old.dtype)
                new[: self.n] = old[: self.n]
                setattr(self, name, new)
        i = self.n
        self.t_ns[i] = t_ns
        self.vectors[i] = row.vectors
        self.applicable[i] = row.applicable
        self.goal_met[i] = row.goal_met
        self.n += 1


def _first_names(path: str | Path, names: tuple[str, ...]) -> None:
    """The behaviour set of the first ``/lfd/behaviors`` message: known names, none repeated."""
    broken = f"{path}: broken /lfd/behaviors"
    if not names or len(names) > MAX_BEHAVIORS or len(set(names)) != len(names):
        raise LogError(f"{broken}: it names {len(names)} behaviours or repeats one; segment the demo again")
    bad = [n for n in names if not _is_behavior(n)]
    if bad:
        raise LogError(f"{broken}: unknown behaviour {bad[0][:40]!r}; segment the demo again")


class _SegmentedBuilder:
    """A :class:`SegmentedRun` built one message at a time: ``feed`` each ``/lfd/*`` message in
    log-time order, then ``finish``.

    Memory is the per-step arrays (``N × K``), nothing per message. The messages are read by the
    decoders of :mod:`lfdfuse.log.lfd`, which check what their schemas state; this checks what
    the schemas cannot (known behaviours, one behaviour set, BACs that agree with the
    applicability bits, contiguous segments).
    """

    def __init__(self, path: str | Path, info: FileInfo) -> None:
        if "/lfd/behaviors" not in info.channels:
            require_lfdfuse_log(path)  # a robot log: the first missing step is import, not segment
            raise LogError(f"{path} is not segmented (no /lfd/behaviors): run `lfdfuse segment {path}` first")
        self.path = path
        self.metadata = info.metadata.get(PROVENANCE, {})
        self.capacity = info.channels["/lfd/behaviors"][2]
        self.cols: _Columns | None = None
        self.demo: list[tuple[float, float]] = []
        self.informative: list[bool] = []
        self.bac: list[int] = []
        self.seg: list[tuple[int, str | None]] = []

    def feed(self, topic: str, t: int, data: bytes) -> None:
        """One message (its log time is checked here: a caller's iterator need not)."""
        check_log_time(self.path, topic, t)
        try:
            self._decode(topic, t, data)
        except MessageError as exc:
            raise LogError(
                f"{self.path}: a {topic} message at t={t} ns: {exc}; segment the demo again"
            ) from exc

    def _decode(self, topic: str, t: int, data: bytes) -> None:
        if topic == "/lfd/behaviors":
            row = lfd.BehaviorRow.decode(data)
            if self.cols is None:
                _first_names(self.path, row.names)
                self.cols = _Columns(row.names, self.capacity)
            elif row.names != self.cols.names:
                raise LogError(
                    f"{self.path}: /lfd/behaviors changes its behaviour set; segment the demo again"
                )
            self.cols.append(t, row)
        elif topic == "/lfd/demo":
            d = lfd.DemoHeading.decode(data)
            self.demo.append((d.x, d.y))
            self.informative.append(d.informative)
        elif topic == "/lfd/bac":
            b = lfd.Bac.decode(data).bac
            if b >> MAX_BEHAVIORS:
                raise MessageError(f"bac has bits beyond the {MAX_BEHAVIORS} behaviours a log can hold")
            self.bac.append(b)
        elif topic == "/lfd/segment":
            mark = lfd.SegmentMark.decode(data)
            if mark.index >= 2**31:
                raise MessageError("the segment index is not below 2^31")
            seg = self.seg
            if mark.goal is not None and (not seg or mark.goal != seg[-1][1]) and not _is_behavior(mark.goal):
                raise MessageError(f"the segment goal {mark.goal[:40]!r} is not a behaviour")
            seg.append((mark.index, mark.goal))

    def finish(self) -> SegmentedRun:
        path, cols, demo, seg = self.path, self.cols, self.demo, self.seg
        n = 0 if cols is None else cols.n
        if cols is None or n == 0 or not (len(demo) == len(self.bac) == len(seg) == n):
            raise LogError(f"{path}: the /lfd/* channels are incomplete; segment the demo again")
        bac_arr = np.array(self.bac, dtype=np.int64)
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
            informative=np.array(self.informative, dtype=bool),
            bac=bac_arr,
            segment_of=seg_of,
            segments=tuple(segs),
            metadata=self.metadata,
        )


def read_segmented(path: str | Path) -> SegmentedRun:
    """Load the ``/lfd/*`` channels of a segmented log; a clear error if there are none or they are
    broken (see :class:`_SegmentedBuilder`). One pass over those channels."""
    builder = _SegmentedBuilder(path, file_info(path))
    for topic, _s, _enc, t, data in iter_records(path, topics=list(lfd.SEGMENT_TOPICS), check_times=False):
        builder.feed(topic, t, data)
    return builder.finish()


def read_segmented_and_run(path: str | Path) -> tuple[SegmentedRun, Run]:
    """:func:`read_segmented` and :func:`~lfdfuse.log.reader.read_run` of one log, from one pass
    over its messages (sub-goals learn from both).

    The errors are theirs, in their order: the run's first error waits until the segmented
    channels have been read whole, so a log broken in both reports what ``read_segmented``
    reports. Only damage to the file itself is reported where the one pass meets it, which may
    be before a broken ``/lfd/*`` message that ``read_segmented`` would have reported first.
    """
    info = file_info(path)
    segmented = _SegmentedBuilder(path, info)
    run: RunBuilder | None = None
    run_error: LogError | None = None
    try:
        run = run_builder(path, info)
    except LogError as exc:
        run_error = exc
    own = frozenset(lfd.SEGMENT_TOPICS)
    topics = [*lfd.SEGMENT_TOPICS, *RUN_TOPICS]
    for topic, _s, enc, t, data in iter_records(path, topics=topics, check_times=False):
        if topic in own:
            segmented.feed(topic, t, data)
        elif run is not None:
            try:
                run.feed(topic, enc, t, data)
            except LogError as exc:
                run, run_error = None, exc  # the run's reading stops at its first error, as read_run's
    seg = segmented.finish()
    if run_error is not None:
        raise run_error
    assert run is not None
    return seg, finish_run(path, info, run)


#: who drove each tick of a ``teleop --table`` log (DESIGN §5): ``network`` or ``person``
AUTHORITY_TOPIC = lfd.Authority.TOPIC


def network_ticks(path: str | Path, when_ns: np.ndarray) -> np.ndarray | None:
    """Per time of ``when_ns (N,)`` whether the learned network drove then (``/lfd/authority``
    held: the latest message at or before it, the first before the first), or None when the log
    has no such channel (a plain demo: the teacher drove throughout)."""
    if AUTHORITY_TOPIC not in file_info(path).channels:
        return None
    t: list[int] = []
    net: list[bool] = []
    at = 0
    try:
        for _topic, _s, at, data in iter_messages(path, topics=[AUTHORITY_TOPIC]):
            t.append(at)
            net.append(not lfd.decode_authority(data).person)
    except MessageError as exc:
        raise LogError(f"{path}: a {AUTHORITY_TOPIC} message at t={at} ns: {exc}") from exc
    if not t:
        return None
    order = np.argsort(np.array(t, dtype=np.int64), kind="stable")
    ts, flags = np.array(t, dtype=np.int64)[order], np.array(net, dtype=bool)[order]
    return np.asarray(flags[hold(ts, when_ns)])


def person_ticks(path: str | Path, when_ns: np.ndarray) -> np.ndarray | None:
    """Per time of ``when_ns (N,)`` whether a person drove then (:func:`network_ticks` negated),
    or None when the log does not say."""
    net = network_ticks(path, when_ns)
    return None if net is None else ~net


#: the network's active step of each tick of a run (DESIGN §5), kept by segment for corrections
STEP_TOPIC = lfd.NetworkStep.TOPIC


def network_steps(path: str | Path, when_ns: np.ndarray) -> tuple[str | None, ...] | None:
    """Per time of ``when_ns (N,)`` the network's active step (``/lfd/step`` held: nested names
    joined by ``/``, None once the task is complete), or None when the log has no such channel."""
    if STEP_TOPIC not in file_info(path).channels:
        return None
    t: list[int] = []
    names: list[str | None] = []
    at = 0
    try:
        for _topic, _s, at, data in iter_messages(path, topics=[STEP_TOPIC]):
            t.append(at)
            names.append(lfd.NetworkStep.decode(data).step)
    except MessageError as exc:
        raise LogError(f"{path}: a {STEP_TOPIC} message at t={at} ns: {exc}") from exc
    if not t:
        return None
    ts = np.array(t, dtype=np.int64)
    order = np.argsort(ts, kind="stable")
    held = order[hold(ts[order], when_ns)]
    return tuple(names[int(i)] for i in held)


def segmentation_of(seg: SegmentedRun) -> Segmentation:
    return Segmentation(seg.segments, seg.segment_of, seg.bac)
