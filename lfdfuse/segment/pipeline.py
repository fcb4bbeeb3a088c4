"""Segmentation of a demonstration (paper Section IV-A).

A new *goal segment* starts whenever the goal of any behaviour becomes met (rising edge); the
same goal met twice gives two segments. Inside a segment a new *BAC sub-segment* starts whenever
any precondition flips. The demonstrated heading comes from ``/cmd_vel`` held to each scan time,
through the inverse of the vector ↔ command mapping; steps where the robot neither moves nor
turns carry no heading and are kept out of estimation.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import orjson
import yaml

from lfdfuse import __version__
from lfdfuse.behaviors.primitives import (
    ATTRACT,
    DEFAULT_PRESET,
    BehaviorOutputs,
    BehaviorParams,
    Observations,
    compute,
    resolve_behaviors,
)
from lfdfuse.control.drive import DriveParams, command_to_vector
from lfdfuse.errors import LogError
from lfdfuse.log import LogWriter
from lfdfuse.log.messages import stamp
from lfdfuse.log.reader import Run, hold, iter_attachments, iter_raw, read_run
from lfdfuse.log.writer import PROVENANCE

LFD_TOPICS = {
    "/lfd/behaviors": "lfdfuse.BehaviorOutputs",
    "/lfd/demo": "lfdfuse.DemoHeading",
    "/lfd/bac": "lfdfuse.Bac",
    "/lfd/segment": "lfdfuse.GoalSegment",
}


@dataclass(frozen=True)
class GoalSegment:
    """Steps ``[start, stop)`` of the demonstration, ended by ``goal`` (None: no goal reached)."""

    index: int
    start: int
    stop: int
    goal: str | None

    @property
    def target(self) -> str | None:
        return self.goal[len(ATTRACT) :] if self.goal and self.goal.startswith(ATTRACT) else None


@dataclass(frozen=True)
class Segmentation:
    """Goal segments and per-step BACs of a demonstration."""

    segments: tuple[GoalSegment, ...]
    segment_of: np.ndarray  # (N,) segment index of every step
    bac: np.ndarray  # (N,) int64 bit mask

    def bac_runs(self, seg: GoalSegment) -> list[tuple[int, int, int]]:
        """BAC sub-segments ``(bac, start, stop)`` of one goal segment, in time order."""
        b = self.bac[seg.start : seg.stop]
        if len(b) == 0:
            return []
        cuts = np.nonzero(np.diff(b))[0] + 1
        starts = np.concatenate([[0], cuts])
        stops = np.concatenate([cuts, [len(b)]])
        return [
            (int(b[s]), seg.start + int(s), seg.start + int(e)) for s, e in zip(starts, stops, strict=True)
        ]


def segment_goals(
    goal_met: np.ndarray, names: tuple[str, ...], *, refractory_steps: int = 10
) -> list[tuple[int, str]]:
    """Goal achievements ``(step, behaviour)``: rising edges of ``goal_met (N, K)``.

    A goal that flickers (met, unmet for fewer than ``refractory_steps``, met again) is one
    achievement, not two. Achievements at the same step are ordered by behaviour index.
    """
    n, k = goal_met.shape
    events: list[tuple[int, int]] = []
    for j in range(k):
        col = goal_met[:, j]
        prev = np.concatenate([[False], col[:-1]])
        rises = np.nonzero(col & ~prev)[0]
        last_met = -(10**9)
        for s in rises:
            falls_before = np.nonzero(col[:s])[0]
            last_met = int(falls_before[-1]) if len(falls_before) else -(10**9)
            if s - last_met > refractory_steps:
                events.append((int(s), j))
    events.sort()
    return [(s, names[j]) for s, j in events]


def segment_outputs(outputs: BehaviorOutputs, *, refractory_steps: int = 10) -> Segmentation:
    """Goal segments and BACs from behaviour outputs."""
    n = outputs.applicable.shape[0]
    events = segment_goals(outputs.goal_met, outputs.names, refractory_steps=refractory_steps)
    segments: list[GoalSegment] = []
    start = 0
    for step, goal in events:
        if step + 1 <= start:
            continue  # two goals met at the same step: the first one ends the segment
        segments.append(GoalSegment(len(segments), start, step + 1, goal))
        start = step + 1
    if start < n:
        segments.append(GoalSegment(len(segments), start, n, None))
    seg_of = np.zeros(n, dtype=np.int64)
    for s in segments:
        seg_of[s.start : s.stop] = s.index
    return Segmentation(tuple(segments), seg_of, outputs.bac)


def target_names_of(run: Run) -> list[str]:
    """Targets of the run's world (attached world file), else those the camera ever saw."""
    if run.world_yaml:
        data = yaml.safe_load(run.world_yaml) or {}
        names = [str(t["name"]) for t in data.get("targets") or [] if isinstance(t, dict) and "name" in t]
        if names:
            return names
    seen: list[str] = []
    for dets in run.detections:
        for d in dets:
            if d.name not in seen:
                seen.append(d.name)
    return seen


def observations_of(run: Run) -> Observations:
    sg = run.sonar_geometry
    return Observations.from_detections(
        ranges_m=run.ranges_m,
        geometry=run.geometry,
        detections=run.detections,
        target_names=target_names_of(run),
        sonar_m=run.sonar_m,
        sonar_angles_rad=None if sg is None else sg.angles,
        sonar_max_m=math.inf if sg is None else sg.max_range_m,
    )


def demonstrated(run: Run, drive: DriveParams) -> tuple[np.ndarray, np.ndarray]:
    """``V_r (N, 2)`` and the informative mask ``(N,)`` on the scan clock."""
    if len(run.cmd_t_ns) == 0:
        raise LogError("the log has no /cmd_vel messages")
    order = np.argsort(run.cmd_t_ns, kind="stable")  # real logs arrive out of order
    ct, cv, cw = run.cmd_t_ns[order], run.cmd_v_mps[order], run.cmd_omega_rps[order]
    idx = hold(ct, run.t_ns)
    before = run.t_ns < ct[0]
    vr, ok = command_to_vector(cv[idx], cw[idx], drive)
    return vr, ok & ~before & np.isfinite(cv[idx]) & np.isfinite(cw[idx])


@dataclass(frozen=True)
class SegmentResult:
    names: tuple[str, ...]
    segmentation: Segmentation
    t_ns: np.ndarray
    informative: np.ndarray
    out: str


def segment_file(
    src: str | Path,
    *,
    out: str | Path,
    behaviors: str = DEFAULT_PRESET,
    params: BehaviorParams | None = None,
    drive: DriveParams = DriveParams(),
) -> SegmentResult:
    """Read a demo log, compute behaviours, segment, and write the segmented log to ``out``."""
    run = read_run(src)
    if len(run) == 0:
        raise LogError(f"{src}: the log is empty")
    obs = observations_of(run)
    names = resolve_behaviors(behaviors, obs.target_names)
    if params is None:
        reach = float(run.metadata.get("camera_reach_m", BehaviorParams().reach_m))
        params = BehaviorParams(reach_m=reach)
    outputs = compute(obs, names, params)
    segm = segment_outputs(outputs)
    vr, ok = demonstrated(run, drive)
    if Path(out).resolve() == Path(src).resolve():
        raise LogError("the output must not overwrite the input")
    meta = dict(run.metadata)
    meta.update(
        {
            "segment_behaviors": ",".join(names),
            "segment_version": __version__,
            "d_max_m": repr(params.d_max_m),
        }
    )
    with LogWriter(out, metadata=meta, topics=dict(LFD_TOPICS)) as log:
        for name, media, data in iter_attachments(src):
            log.attach(name, media, data)
        lfd = _lfd_messages(run.t_ns, outputs, segm, vr, ok)
        k = 0
        # copy every input channel (but our own, which we replace) interleaved in time order
        for raw in iter_raw(src, exclude_prefix="/lfd/"):
            while k < len(lfd) and lfd[k][1] < raw.log_time_ns:
                log.write_raw(*lfd[k])
                k += 1
            log.copy(raw)
        for item in lfd[k:]:
            log.write_raw(*item)
    return SegmentResult(tuple(names), segm, run.t_ns, ok, str(out))


def _lfd_messages(
    t_ns: np.ndarray, outputs: BehaviorOutputs, segm: Segmentation, vr: np.ndarray, ok: np.ndarray
) -> list[tuple[str, int, bytes]]:
    names = outputs.names
    seg_goal = {s.index: (s.goal, s.target) for s in segm.segments}
    out: list[tuple[str, int, bytes]] = []
    vec = np.round(outputs.vectors, 6)
    for i, t in enumerate(t_ns.tolist()):
        ts = stamp(int(t))
        app = outputs.applicable[i]
        out.append(
            (
                "/lfd/behaviors",
                t,
                orjson.dumps(
                    {
                        "timestamp": ts,
                        "behaviors": [
                            {
                                "name": n,
                                "x": float(vec[i, j, 0]),
                                "y": float(vec[i, j, 1]),
                                "applicable": bool(app[j]),
                                "goal_met": bool(outputs.goal_met[i, j]),
                            }
                            for j, n in enumerate(names)
                        ],
                    }
                ),
            )
        )
        out.append(
            (
                "/lfd/demo",
                t,
                orjson.dumps(
                    {
                        "timestamp": ts,
                        "x": float(vr[i, 0]),
                        "y": float(vr[i, 1]),
                        "heading_rad": math.atan2(vr[i, 1], vr[i, 0]),
                        "informative": bool(ok[i]),
                    }
                ),
            )
        )
        out.append(
            (
                "/lfd/bac",
                t,
                orjson.dumps(
                    {
                        "timestamp": ts,
                        "bac": int(segm.bac[i]),
                        "applicable": [n for j, n in enumerate(names) if app[j]],
                    }
                ),
            )
        )
        g, tg = seg_goal[int(segm.segment_of[i])]
        out.append(
            (
                "/lfd/segment",
                t,
                orjson.dumps({"timestamp": ts, "index": int(segm.segment_of[i]), "goal": g, "target": tg}),
            )
        )
    return out


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
    """Load the ``/lfd/*`` channels of a segmented log; a clear error if there are none."""
    from lfdfuse.log.reader import file_info, iter_messages

    info = file_info(path)
    if "/lfd/behaviors" not in info.channels:
        raise LogError(f"{path} is not segmented (no /lfd/behaviors): run `lfdfuse segment {path}` first")
    rows: dict[str, list[tuple[int, dict]]] = {t: [] for t in LFD_TOPICS}  # type: ignore[type-arg]
    for topic, _s, t, data in iter_messages(path, topics=list(LFD_TOPICS)):
        rows[topic].append((t, orjson.loads(data)))
    beh = rows["/lfd/behaviors"]
    n = len(beh)
    if n == 0 or any(len(rows[t]) != n for t in LFD_TOPICS):
        raise LogError(f"{path}: the /lfd/* channels are incomplete; segment the demo again")
    names = tuple(b["name"] for b in beh[0][1]["behaviors"])
    k = len(names)
    vec = np.array([[(b["x"], b["y"]) for b in m["behaviors"]] for _, m in beh]).reshape(n, k, 2)
    app = np.array([[b["applicable"] for b in m["behaviors"]] for _, m in beh], dtype=bool).reshape(n, k)
    goal = np.array([[b["goal_met"] for b in m["behaviors"]] for _, m in beh], dtype=bool).reshape(n, k)
    demo = np.array([(m["x"], m["y"]) for _, m in rows["/lfd/demo"]])
    ok = np.array([m["informative"] for _, m in rows["/lfd/demo"]], dtype=bool)
    bac = np.array([m["bac"] for _, m in rows["/lfd/bac"]], dtype=np.int64)
    seg_of = np.array([m["index"] for _, m in rows["/lfd/segment"]], dtype=np.int64)
    segs: list[GoalSegment] = []
    for idx in np.unique(seg_of):
        where = np.nonzero(seg_of == idx)[0]
        segs.append(
            GoalSegment(
                int(idx), int(where[0]), int(where[-1]) + 1, rows["/lfd/segment"][int(where[0])][1]["goal"]
            )
        )
    meta = info.metadata.get(PROVENANCE, {})
    return SegmentedRun(
        names,
        np.array([t for t, _ in beh], dtype=np.int64),
        vec,
        app,
        goal,
        demo,
        ok,
        bac,
        seg_of,
        tuple(segs),
        meta,
    )


def bac_summary(segm: Segmentation, seg: GoalSegment) -> list[tuple[int, int, int]]:
    """``(bac, samples, runs)`` of one goal segment, most samples first."""
    runs = segm.bac_runs(seg)
    samples: Counter[int] = Counter()
    count: Counter[int] = Counter()
    for b, s, e in runs:
        samples[b] += e - s
        count[b] += 1
    return sorted(((b, samples[b], count[b]) for b in samples), key=lambda x: (-x[1], x[0]))


def segmentation_of(seg: SegmentedRun) -> Segmentation:
    return Segmentation(seg.segments, seg.segment_of, seg.bac)
