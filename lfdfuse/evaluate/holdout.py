"""Held-out prediction (DESIGN §12): how well does a learned fusion explain the rest of a demo?

The first part of a segmented demo (by time) trains a fusion table; every informative step of
the held-out rest gets a predicted heading, and the mean absolute error to the demonstrated
heading is reported per method, with a bootstrap interval:

* ``fused`` – the default estimator; ``nnls`` and ``arbitration`` – the baselines;
* ``straight`` – always straight ahead (what a robot that ignores its sensors would do);
* ``previous`` – the last demonstrated heading before the step (a persistence baseline: it
  needs the teacher's own command a tick ago, which no controller has when it drives alone);
* ``oracle`` – the default estimator fitted on the held-out steps themselves: the floor for
  any fusion of these primitives on those steps.

Predictions use the weights the runtime would use (DESIGN §8): the step's row for the BAC, else
the step's default weights, else the table's; a held-out goal segment that training never
reached uses the table's default weights.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.pipeline import EstimateOptions, Method, estimate_run
from lfdfuse.estimate.replay import fused_vectors
from lfdfuse.network.table import FusionTable
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.read import SegmentedRun

METHODS: tuple[str, ...] = ("fused", "nnls", "arbitration", "straight", "previous", "oracle")


@dataclass(frozen=True)
class MethodScore:
    heading_error_deg: float  # mean absolute heading error on informative held-out steps
    ci95_deg: tuple[float, float]  # bootstrap interval of that mean
    median_deg: float
    turning_error_deg: float  # the same mean over steps where the teacher turned (|heading| ≥ 10°)


#: a held-out step counts as a turn when the demonstrated heading is at least this far off straight
TURN_RAD = math.radians(10.0)


@dataclass(frozen=True)
class Evaluation:
    train_steps: int  # informative steps the tables were fitted on
    test_steps: int  # informative held-out steps scored
    turning_steps: int  # of those, steps where the teacher turned
    holdout: float
    lag_s: float | None  # the command lag the demo was segmented with (metadata), if known
    methods: dict[str, MethodScore] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "train_steps": self.train_steps,
            "test_steps": self.test_steps,
            "turning_steps": self.turning_steps,
            "holdout": self.holdout,
            "lag_s": self.lag_s,
            "methods": {
                name: {
                    "heading_error_deg": round(s.heading_error_deg, 3),
                    "ci95_deg": [round(s.ci95_deg[0], 3), round(s.ci95_deg[1], 3)],
                    "median_deg": round(s.median_deg, 3),
                    "turning_error_deg": round(s.turning_error_deg, 3),
                }
                for name, s in self.methods.items()
            },
        }


def slice_run(run: SegmentedRun, start: int, stop: int) -> SegmentedRun:
    """Steps ``[start, stop)`` of a segmented run; goal segments clipped, indices kept."""
    segs = tuple(
        GoalSegment(
            s.index,
            max(s.start, start) - start,
            min(s.stop, stop) - start,
            s.goal if s.stop <= stop else None,
        )
        for s in run.segments
        if s.stop > start and s.start < stop
    )
    sl = slice(start, stop)
    return replace(
        run,
        t_ns=run.t_ns[sl],
        vectors=run.vectors[sl],
        applicable=run.applicable[sl],
        goal_met=run.goal_met[sl],
        demo=run.demo[sl],
        informative=run.informative[sl],
        bac=run.bac[sl],
        segment_of=run.segment_of[sl],
        segments=segs,
    )


def predict(table: FusionTable, run: SegmentedRun, steps: np.ndarray, segment_offset: int = 0) -> np.ndarray:
    """Predicted headings (rad) of ``steps`` of ``run`` by ``table``, fused as the runtime fuses."""
    fused = fused_vectors(table, run, steps, segment_offset=segment_offset)
    moving = np.hypot(fused[:, 0], fused[:, 1]) > 1e-9
    return np.where(moving, np.arctan2(fused[:, 1], fused[:, 0]), 0.0)


def _score(
    errors_rad: np.ndarray, turning: np.ndarray, rng: np.random.Generator, resamples: int = 1000
) -> MethodScore:
    e = np.degrees(np.abs(errors_rad))
    boots = e[rng.integers(0, len(e), (resamples, len(e)))].mean(axis=1)
    lo, hi = np.percentile(boots, [2.5, 97.5])
    turn = float(e[turning].mean()) if turning.any() else math.nan
    return MethodScore(float(e.mean()), (float(lo), float(hi)), float(np.median(e)), turn)


def _wrap(a: np.ndarray) -> np.ndarray:
    return np.asarray(np.arctan2(np.sin(a), np.cos(a)))


def evaluate(
    run: SegmentedRun,
    *,
    holdout: float = 0.3,
    seed: int = 0,
    opts: EstimateOptions | None = None,
    progress: Callable[[float, float], None] | None = None,
) -> Evaluation:
    """Fit on the first ``1 − holdout`` of the steps, score every method on the rest."""
    if not (math.isfinite(holdout) and 0.0 < holdout < 1.0):
        raise ConfigError(f"--holdout must be a fraction between 0 and 1, got {holdout}")
    n = len(run.t_ns)
    cut = int(math.floor(n * (1.0 - holdout)))
    train, test = slice_run(run, 0, cut), slice_run(run, cut, n)
    test_steps = np.nonzero(test.informative)[0]
    n_train = int(train.informative.sum())
    if n_train < 10 or len(test_steps) < 10:
        raise ConfigError(
            f"too few informative steps to evaluate ({n_train} to train, {len(test_steps)} held out; need 10 each)"
        )
    base = opts or EstimateOptions(seed=seed)
    demo = np.arctan2(test.demo[test_steps, 1], test.demo[test_steps, 0])
    offset = int(test.segment_of[0]) if len(test.segment_of) else 0
    predictions: dict[str, np.ndarray] = {}
    fits = [("fused", train, base), ("nnls", train, replace(base, method=Method.NNLS))]
    fits += [("arbitration", train, replace(base, method=Method.ARBITRATION)), ("oracle", test, base)]
    for k, (name, part, eo) in enumerate(fits):
        table, _, _ = estimate_run(part, opts=eo, name=name)
        predictions[name] = predict(table, test, test_steps, segment_offset=offset if part is test else 0)
        if progress is not None:
            progress(k + 1.0, len(fits) + 1.0)
    predictions["straight"] = np.zeros(len(test_steps))
    # the last demonstrated heading before each held-out step (informative ones only)
    all_inf = np.nonzero(run.informative)[0]
    headings = np.arctan2(run.demo[all_inf, 1], run.demo[all_inf, 0])
    where = np.searchsorted(all_inf, test_steps + cut, side="left") - 1
    predictions["previous"] = np.where(where >= 0, headings[np.clip(where, 0, None)], 0.0)
    rng = np.random.default_rng(seed)
    turning = np.abs(demo) >= TURN_RAD
    scores = {name: _score(_wrap(predictions[name] - demo), turning, rng) for name in METHODS}
    lag = run.metadata.get("segment_lag_s")
    return Evaluation(
        train_steps=n_train,
        test_steps=len(test_steps),
        turning_steps=int(turning.sum()),
        holdout=holdout,
        lag_s=float(lag) if lag is not None else None,
        methods=scores,
    )


def reading(ev: Evaluation) -> list[str]:
    """What the numbers mean, in plain sentences (the CLI prints them under the table)."""
    m = {k: v.heading_error_deg for k, v in ev.methods.items()}
    lines = []
    gap = m["fused"] - m["oracle"]
    lines.append(
        f"fused is {gap:.1f}° above the oracle (the best fusion of these primitives on the held-out steps)."
    )
    if m["oracle"] >= m["straight"] - 0.5:
        turn = {k: v.turning_error_deg for k, v in ev.methods.items()}
        lines.append(
            "even the oracle does not beat 'straight' on average: the teacher mostly drove straight here"
            f" ({ev.test_steps - ev.turning_steps} of {ev.test_steps} steps within 10° of ahead)."
        )
        if ev.turning_steps and turn["fused"] < turn["straight"]:
            lines.append(
                f"where the teacher turned ({ev.turning_steps} steps), fused errs {turn['fused']:.1f}°"
                f" against straight's {turn['straight']:.1f}°: the primitives explain the turns."
            )
    elif m["fused"] < m["straight"]:
        lines.append(
            f"fused beats 'straight' by {m['straight'] - m['fused']:.1f}°: the sensors explain the steering."
        )
    else:
        lines.append(
            "fused does not beat 'straight' although the oracle does: the learned weights do not transfer in time."
        )
    lines.append(
        "'previous' copies the teacher's own last command: a persistence bound no controller driving alone can use."
    )
    return lines
