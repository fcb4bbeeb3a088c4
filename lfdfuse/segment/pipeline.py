"""``segment``: a demo log in, the same log with the ``/lfd/*`` channels out (paper Section IV-A).

Reads the run, computes the behaviour primitives over the whole log at once, splits it at goal
achievements and BAC changes (:mod:`~lfdfuse.segment.goals`), pairs every scan with the
demonstrated heading (:mod:`~lfdfuse.segment.demo`), and writes every input channel through
(of a correction's ``/lfd/*`` ones only who drove and the network's step, ``/lfd/authority``
and ``/lfd/step``) with ``/lfd/behaviors``, ``/lfd/demo``, ``/lfd/bac`` and ``/lfd/segment`` interleaved in time.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from lfdfuse import __version__
from lfdfuse.behaviors.primitives import (
    DEFAULT_PRESET,
    BehaviorOutputs,
    BehaviorParams,
    BehaviorState,
    Observations,
    compute,
    resolve_behaviors,
)
from lfdfuse.control.command import DriveParams
from lfdfuse.errors import LogError
from lfdfuse.log import lfd
from lfdfuse.log.reader import check_log_file, iter_attachments, iter_raw, meta_float, read_run
from lfdfuse.log.writer import LogWriter
from lfdfuse.progress import Progress, part, tell
from lfdfuse.robot.limits import stated_limits
from lfdfuse.segment.commands import detect_commands
from lfdfuse.segment.demo import demonstrated, lag_ns_of, observations_of
from lfdfuse.segment.goals import Segmentation, segment_outputs
from lfdfuse.segment.lag import (
    CANDIDATE_LAGS_S,
    MIN_PRESSES,
    LagFit,
    best_fit,
    best_lag,
    lag_fits,
    press_lag_fits,
)
from lfdfuse.segment.read import AUTHORITY_TOPIC, STEP_TOPIC, network_ticks
from lfdfuse.sim.robot import RobotParams
from lfdfuse.sources.importers import require_lfdfuse_log

#: ``/lfd/*`` channels of a correction (``teleop --table``, it says who drove) that segment
#: copies through: who drove each tick and the network step it was in (estimate learns a
#: correction in the sub-step the network was in); any other log's ``/lfd/*`` are replaced
_KEPT = frozenset({AUTHORITY_TOPIC, STEP_TOPIC})

# the shares of a segment run's time (a 30-minute demo, profiled): reading the log, the
# behaviour primitives, the lag search, and writing the segmented copy
_READ, _COMPUTE, _LAG, _WRITE = 0.25, 0.05, 0.04, 0.66


@dataclass(frozen=True)
class SegmentResult:
    names: tuple[str, ...]
    segmentation: Segmentation
    t_ns: np.ndarray
    informative: np.ndarray
    out: str
    lag_s: float = 0.0
    lag_fits: tuple[LagFit, ...] = ()  # fit error per candidate lag (empty when not measured)

    @property
    def step_s(self) -> float:
        """The demo's control period (s): see :func:`step_s_of`."""
        return step_s_of(self.t_ns)

    @property
    def best_lag(self) -> LagFit | None:
        """The candidate lag whose fits explain the demo best (smallest heading error; the
        shorter lag on a tie), or None when no lag was measured or none had informative steps."""
        return best_fit(self.lag_fits)

    @property
    def fit_at_lag(self) -> LagFit | None:
        """The fit at the lag this segmentation used, when that lag was among the candidates."""
        return next((f for f in self.lag_fits if f.steps > 0 and abs(f.lag_s - self.lag_s) < 1e-9), None)


def step_s_of(t_ns: np.ndarray) -> float:
    """The control period (s) of steps stamped ``t_ns`` (N,): the median gap between them, or
    the simulated robot's period when there are fewer than two steps.

    >>> step_s_of(np.array([0, 100_000_000, 200_000_000, 350_000_000]))
    0.1
    >>> step_s_of(np.array([], dtype=np.int64)) == RobotParams().dt_s
    True
    """
    if len(t_ns) < 2:
        return RobotParams().dt_s
    return float(np.median(np.diff(t_ns))) / 1e9


def segment_file(
    src: str | Path,
    *,
    out: str | Path,
    behaviors: str = DEFAULT_PRESET,
    params: BehaviorParams | None = None,
    drive: DriveParams | None = None,
    lag_s: float | None = 0.0,
    measure_lag: bool = True,
    commands: str = "auto",
    progress: Progress | None = None,
) -> SegmentResult:
    """Read a demo log, compute behaviours, segment, and write the segmented log to ``out``.

    The robot's limits for the command → heading mapping come from ``drive``, else from the
    log's provenance (``v_max_mps``, ``omega_max_rps``: an imported robot's own), else the
    simulated robot's. ``lag_s`` None (``--lag auto``, the command line's default) pairs each scan with the command of the
    best-explaining lag (:mod:`~lfdfuse.segment.lag`); ``commands`` (``auto``, ``continuous``,
    ``discrete``) is the command model estimate will use (:mod:`~lfdfuse.segment.commands`). A lag outside the lags the search covers is refused: the summary could
    not say whether it explains the demo. ``progress`` hears the whole job's share done
    (reading, the primitives, the lag search and writing, by their measured cost).
    """
    lo, hi = min(CANDIDATE_LAGS_S), max(CANDIDATE_LAGS_S)
    if lag_s is not None and math.isfinite(lag_s) and not lo <= lag_s <= hi:
        raise LogError(
            f"--lag {lag_s:g} is outside the {lo:g}–{hi:g} s the lag search covers (teachers react"
            " within a second): give a lag in that range"
        )
    check_log_file(src)
    if Path(out).resolve() == Path(src).resolve():
        raise LogError(f"the output {out} would overwrite the input: give another -o")
    require_lfdfuse_log(src)
    run = read_run(src, progress=part(progress, start=0.0, size=_READ, total=1.0))
    if drive is None:
        drive = drive_params_of(run.metadata)
    if len(run) == 0:
        raise LogError(f"{src}: the log is empty")
    obs = observations_of(run)
    names = resolve_behaviors(behaviors, obs.target_names)
    if params is None:
        reach = meta_float(run.metadata, "camera_reach_m", BehaviorParams().reach_m)
        params = BehaviorParams(reach_m=reach)
    outputs = compute_in_chunks(obs, names, params)
    tell(progress, _READ + _COMPUTE, 1.0)
    segm = segment_outputs(outputs)
    # a correction log (teleop --table): the network's own commands are the learner's, not the
    # teacher's, and say nothing of how the person commands (a run the network drove throughout
    # teaches nothing either way: all its commands decide)
    by_net = network_ticks(src, run.cmd_t_ns)
    person = slice(None) if by_net is None or by_net.all() else ~by_net
    mode = detect_commands(
        run.cmd_v_mps[person], run.cmd_omega_rps[person], run.metadata, run.topics, commands
    )
    fits = tuple(lag_fits(run, outputs, drive)) if measure_lag or lag_s is None else ()
    if lag_s is None:
        lag_s = best_lag(fits)
        if mode == "discrete":  # a decision answers the scene one reaction before its press
            presses = tuple(press_lag_fits(run, outputs, drive, lag_s))
            if min((f.steps for f in presses), default=0) >= MIN_PRESSES:
                fits, lag_s = presses, best_lag(presses)
    tell(progress, _READ + _COMPUTE + _LAG, 1.0)
    lag_ns = lag_ns_of(lag_s)
    vr, ok = demonstrated(run, drive, lag_ns=lag_ns)
    # the command paired with a scan is the one in force ``lag`` later, so is its driver
    net = network_ticks(src, run.t_ns + np.int64(lag_ns))
    if net is not None:
        ok = ok & ~net
    meta = dict(run.metadata)
    meta.update(
        {
            "segment_behaviors": ",".join(names),
            "segment_version": __version__,
            "d_max_m": repr(params.d_max_m),
            "segment_lag_s": repr(lag_s),
            "segment_commands": mode,
        }
    )
    if net is not None:
        meta["segment_network_ticks"] = str(int(net.sum()))
    with LogWriter(out, metadata=meta, topics=dict(lfd.SEGMENT_TOPICS)) as log:
        for name, media, data in iter_attachments(src):
            log.attach(name, media, data)
        # encoded lazily (a list of every message would grow with the log)
        lfd_msgs = _lfd_messages(run.t_ns, outputs, segm, vr, ok)
        pending = next(lfd_msgs, None)
        writing = part(progress, start=1.0 - _WRITE, size=_WRITE, total=1.0)
        t0 = int(run.t_ns[0]) if len(run.t_ns) else 0
        span = max(int(run.t_ns[-1]) - t0, 1) if len(run.t_ns) else 1
        # copy every input channel (but our own, which we replace) interleaved in time order
        kept = _KEPT if net is not None else frozenset()
        copied = 0
        for raw in iter_raw(src):
            if raw.topic.startswith("/lfd/") and raw.topic not in kept:
                continue  # ours, replaced (who drove and the network's step are the input's: they stay)
            while pending is not None and pending[1] < raw.log_time_ns:
                log.write_raw(*pending)
                pending = next(lfd_msgs, None)
            log.copy(raw)
            copied += 1
            if writing is not None and copied % 512 == 0:
                writing(min(max(raw.log_time_ns - t0, 0), span), span)
        while pending is not None:
            log.write_raw(*pending)
            pending = next(lfd_msgs, None)
    tell(progress, 1.0, 1.0)
    return SegmentResult(tuple(names), segm, run.t_ns, ok, str(out), lag_s, fits)


def drive_params_of(metadata: dict[str, str]) -> DriveParams:
    """The robot's speed and turn limits from a log's provenance (defaults where absent or invalid)."""
    base = DriveParams()
    v, w = stated_limits(metadata)
    return replace(base, v_max_mps=v or base.v_max_mps, omega_max_rps=w or base.omega_max_rps)


def compute_in_chunks(
    obs: Observations, names: list[str] | tuple[str, ...], params: BehaviorParams, *, rows: int = 2048
) -> BehaviorOutputs:
    """:func:`compute` over a whole log a block of scans at a time, with temporaries of
    ``rows × beams`` instead of ``N × beams``. One :class:`BehaviorState` is carried from block
    to block, so a stateful primitive sees the scans in order as a live run does: the result is
    the same as computing the log in one piece, or tick by tick."""
    n = len(obs.ranges_m)
    state = BehaviorState(names, params)
    if n <= rows:
        return compute(obs, names, params, state)
    parts = [compute(obs.rows(a, min(a + rows, n)), names, params, state) for a in range(0, n, rows)]
    return BehaviorOutputs(
        parts[0].names,
        np.concatenate([p.vectors for p in parts]),
        np.concatenate([p.applicable for p in parts]),
        np.concatenate([p.goal_met for p in parts]),
    )


def _lfd_messages(
    t_ns: np.ndarray, outputs: BehaviorOutputs, segm: Segmentation, vr: np.ndarray, ok: np.ndarray
) -> Iterator[tuple[str, int, bytes]]:
    names = outputs.names
    seg_goal = {s.index: (s.goal, s.target) for s in segm.segments}
    vec = np.round(outputs.vectors, 6)
    for i, t in enumerate(t_ns.tolist()):
        app = outputs.applicable[i]
        s = int(segm.segment_of[i])
        g, tg = seg_goal[s]
        yield ("/lfd/behaviors", t, lfd.encode_behaviors(t, names, vec[i], app, outputs.goal_met[i]))
        yield ("/lfd/demo", t, lfd.encode_demo(t, float(vr[i, 0]), float(vr[i, 1]), bool(ok[i])))
        yield ("/lfd/bac", t, lfd.encode_bac(t, int(segm.bac[i]), [n for j, n in enumerate(names) if app[j]]))
        yield ("/lfd/segment", t, lfd.encode_segment(t, s, g, tg))
