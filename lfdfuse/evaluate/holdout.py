"""Held-out prediction (DESIGN §12): how well does a learned fusion explain the rest of a demo?

The first part of a segmented demo (by time) trains a fusion table; every informative step of
the held-out rest gets a predicted heading, and the mean absolute error to the demonstrated
heading is reported per method, with a bootstrap interval:

* ``fused`` – the default estimator; ``nnls`` and ``arbitration`` – the baselines;
* ``straight`` – always straight ahead (what a robot that ignores its sensors would do);
* ``previous`` – the last demonstrated heading before the step (a persistence baseline: it
  needs the teacher's own command a tick ago, which no controller has when it drives alone);
* ``oracle`` – the default estimator fitted on the held-out steps themselves: the floor for
  any fusion of these primitives on those steps. For a discrete log it reads the held-out
  decisions in the command set of the whole demo (the person's keyboard), as the scores do: a
  held-out part holding one command would otherwise be one bin, which every heading is in.

For a demo of the discrete command model (a person at a keyboard, DESIGN §6) a fitted
method's prediction is read as the person's key press (:mod:`lfdfuse.estimate.keys`): its
heading is the heading of the key whose bin holds the fused heading (the model's median
prediction: a person holding 'forward' is predicted forward, not at the fused vector's few
degrees off), and the held-out *decisions* (:func:`~lfdfuse.estimate.commands.decision_steps`)
are scored too: a fitted method predicts the most probable key given its fused heading, by a
key response (how often the person pressed each key, and how noisily about the fused heading)
fitted on the decisions the method was fitted on; ``straight`` always the most common command of
the training decisions, ``previous`` the command held before the decision; a stop or a reverse
is a command no fusion predicts. ``command_accuracy`` is the share predicted right; fused's key
response of every fit is in ``keys``.

Predictions use the weights the runtime would use (DESIGN §8): the step's row for the BAC, else
the step's default weights, else the table's; a held-out goal segment that training never
reached uses the table's default weights.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.commands import commands_of
from lfdfuse.estimate.keys import fit_key_response, key_heading, key_of
from lfdfuse.estimate.methods import POINT_FITS
from lfdfuse.estimate.model import CommandBins
from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.estimate.replay import fused_vectors
from lfdfuse.network.table import FusionTable
from lfdfuse.progress import Progress
from lfdfuse.progress import part as share
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.read import SegmentedRun

#: what is scored: the default estimator, the point-fit methods (the baselines), then predictors
#: that fit nothing, and the oracle
METHODS: tuple[str, ...] = ("fused", *(m.value for m in POINT_FITS), "straight", "previous", "oracle")


@dataclass(frozen=True)
class MethodScore:
    heading_error_deg: float  # mean absolute heading error on informative held-out steps
    ci95_deg: tuple[float, float]  # bootstrap interval of that mean
    median_deg: float
    turning_error_deg: float  # the same mean over steps where the teacher turned (|heading| ≥ 10°)
    command_accuracy: float | None = None  # discrete logs: share of held-out decisions predicted
    #: k-fold (:mod:`lfdfuse.evaluate.folds`): the mean error of each fold's held-out steps
    fold_errors_deg: tuple[float, ...] | None = None

    @property
    def fold_sd_deg(self) -> float | None:
        """The spread of the fold means (sample standard deviation), k-fold only."""
        f = self.fold_errors_deg
        if f is None:
            return None
        finite = [x for x in f if math.isfinite(x)]
        return float(np.std(finite, ddof=1)) if len(finite) > 1 else math.nan


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
    commands: str = "continuous"  # the command model of the demo
    test_decisions: int | None = None  # discrete logs: held-out decisions scored
    #: distinct demonstrated headings (to 0.1°) among the held-out steps; 1: one constant command
    held_out_headings: int | None = None
    #: ``holdout`` (the last part by time) or ``kfold`` (blocked folds over the decisions: then
    #: ``holdout`` is None, ``train_steps`` the mean over the folds' fits)
    split: str = "holdout"
    folds: int | None = None
    informative_decisions: int | None = None  # k-fold: the decisions the folds were cut over
    #: discrete logs: how the fits' predictions were read as keys, with fused's key response per fit
    keys: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "train_steps": self.train_steps,
            "test_steps": self.test_steps,
            "turning_steps": self.turning_steps,
            "holdout": None if math.isnan(self.holdout) else self.holdout,  # k-fold holds out no part by time
            "lag_s": self.lag_s,
            "commands": self.commands,
            **({} if self.test_decisions is None else {"test_decisions": self.test_decisions}),
            "held_out_headings": self.held_out_headings,
            **(
                {}
                if self.split == "holdout"
                else {
                    "split": self.split,
                    "folds": self.folds,
                    "informative_decisions": self.informative_decisions,
                }
            ),
            **({} if self.keys is None else {"keys": self.keys}),
            "methods": {
                name: {
                    "heading_error_deg": round(s.heading_error_deg, 3),
                    "ci95_deg": [round(s.ci95_deg[0], 3), round(s.ci95_deg[1], 3)],
                    "median_deg": round(s.median_deg, 3),
                    # no turn held out: null, not NaN (which is not JSON)
                    "turning_error_deg": None
                    if math.isnan(s.turning_error_deg)
                    else round(s.turning_error_deg, 3),
                    **(
                        {}
                        if s.command_accuracy is None
                        else {"command_accuracy": round(s.command_accuracy, 4)}
                    ),
                    **({} if s.fold_errors_deg is None else _folds_dict(s)),
                }
                for name, s in self.methods.items()
            },
        }


def _json_float(x: float | None, digits: int = 3) -> float | None:
    return None if x is None or not math.isfinite(x) else round(x, digits)


def _folds_dict(s: MethodScore) -> dict[str, Any]:
    """A k-fold method's fold means and their spread (null where a fold has no score)."""
    return {
        "fold_errors_deg": [_json_float(x) for x in s.fold_errors_deg or ()],
        "fold_sd_deg": _json_float(s.fold_sd_deg),
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
    if len(e) == 0:  # a discrete log may hold decisions but no informative held-out step
        return MethodScore(math.nan, (math.nan, math.nan), math.nan, math.nan)
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
    progress: Progress | None = None,
) -> Evaluation:
    """Fit on the first ``1 − holdout`` of the steps, score every method on the rest."""
    if not (math.isfinite(holdout) and 0.0 < holdout < 1.0):
        raise ConfigError(f"--holdout must be a fraction between 0 and 1, got {holdout}")
    n = len(run.t_ns)
    cut = int(math.floor(n * (1.0 - holdout)))
    train, test = slice_run(run, 0, cut), slice_run(run, cut, n)
    test_steps = np.nonzero(test.informative)[0]
    n_train = int(train.informative.sum())
    base = opts or EstimateOptions(seed=seed)
    cm = commands_of(run, requested=base.commands, recheck_s=base.model.recheck_s)
    if cm.decisions is None:
        if n_train < 10 or len(test_steps) < 10:
            raise ConfigError(
                f"too few informative steps to evaluate ({n_train} to train, {len(test_steps)} held out; need 10 each)"
            )
    else:
        d_train, d_test = (
            int((cm.decisions[:cut] & run.informative[:cut]).sum()),
            int(cm.decisions[cut:].sum()),
        )
        if d_train < 10 or d_test < 10:
            raise ConfigError(
                f"too few decisions to evaluate ({d_train} informative to train, {d_test} held out; need 10 each)"
            )
    demo = np.arctan2(test.demo[test_steps, 1], test.demo[test_steps, 0])
    offset = int(test.segment_of[0]) if len(test.segment_of) else 0
    predictions: dict[str, np.ndarray] = {}
    fits = [("fused", train, base), *((m.value, train, replace(base, method=m)) for m in POINT_FITS)]
    fits.append(("oracle", test, base))
    decided = np.zeros(0, dtype=np.int64) if cm.decisions is None else np.nonzero(cm.decisions[cut:])[0]
    chosen: dict[str, np.ndarray] = {}
    truth = None if cm.bins is None else command_of(cm.bins, run)
    responses: list[dict[str, object]] = []
    for k, (name, part, eo) in enumerate(fits):
        sub = share(progress, start=float(k), size=1.0, total=len(fits) + 1.0)
        # the oracle reads the held-out decisions in the person's command set (the whole demo's),
        # not in the few commands the held-out part happens to hold: a part holding one command
        # would have one bin, every decision in it, and the oracle would be the prior
        keyboard = cm.bins if part is test else None
        table, _, _ = estimate_run(part, opts=eo, name=name, progress=sub, command_set=keyboard)
        off = offset if part is test else 0
        predictions[name] = predict(table, test, test_steps, segment_offset=off)
        if cm.bins is not None and cm.decisions is not None and truth is not None:
            # a person at a keyboard: the key the fit predicts (its own decisions fit the key
            # response) and the heading of the key whose bin holds the prediction
            part_truth = truth[:cut] if part is train else truth[cut:]
            part_dec = cm.decisions[:cut] if part is train else cm.decisions[cut:]
            seen = np.nonzero(part_dec & part.informative)[0]
            at_seen = predict(table, part, seen, segment_offset=off)
            response = fit_key_response(cm.bins, at_seen, part_truth[seen], base.model)
            chosen[name] = response.key(predict(table, test, decided, segment_offset=off), base.model)
            predictions[name] = key_heading(cm.bins, predictions[name])
            if name == "fused":
                responses.append(response.provenance())
    predictions["straight"] = np.zeros(len(test_steps))
    # the last demonstrated heading before each held-out step (informative ones only)
    all_inf = np.nonzero(run.informative)[0]
    headings = np.arctan2(run.demo[all_inf, 1], run.demo[all_inf, 0])
    where = np.searchsorted(all_inf, test_steps + cut, side="left") - 1
    predictions["previous"] = np.where(where >= 0, headings[np.clip(where, 0, None)], 0.0)
    rng = np.random.default_rng(seed)
    turning = np.abs(demo) >= TURN_RAD
    scores = {name: _score(_wrap(predictions[name] - demo), turning, rng) for name in METHODS}
    if cm.bins is not None and cm.decisions is not None and truth is not None:
        train_d = truth[:cut][cm.decisions[:cut]]
        values, counts = np.unique(train_d, return_counts=True)
        chosen["straight"] = np.full(len(decided), values[int(np.argmax(counts))] if len(values) else -1)
        chosen["previous"] = truth[np.maximum(decided + cut - 1, 0)]
        actual = truth[decided + cut]
        scores = {
            name: replace(s, command_accuracy=float((chosen[name] == actual).mean()))
            for name, s in scores.items()
        }
    lag = run.metadata.get("segment_lag_s")
    return Evaluation(
        train_steps=n_train,
        test_steps=len(test_steps),
        turning_steps=int(turning.sum()),
        holdout=holdout,
        lag_s=float(lag) if lag is not None else None,
        methods=scores,
        commands=cm.mode,
        test_decisions=None if cm.decisions is None else len(decided),
        held_out_headings=len(np.unique(np.round(np.degrees(demo), 1))),
        keys=None if cm.bins is None else keys_provenance(responses),
    )


def bin_of(bins: CommandBins, heading: np.ndarray) -> np.ndarray:
    """The command whose bin holds each heading (rad): the one a person would press."""
    return key_of(bins, heading)


def keys_provenance(responses: list[dict[str, object]]) -> dict[str, Any]:
    """How a discrete log's predictions were read (:mod:`lfdfuse.estimate.keys`), and fused's key
    response fitted on each fit's training decisions."""
    return {
        "heading": "the heading of the key whose bin holds the predicted heading",
        "command": "the most probable key given the predicted heading: key shares and noise σ"
        " fitted on the training decisions",
        "fused": responses,
    }


def command_of(bins: CommandBins, run: SegmentedRun) -> np.ndarray:
    """The command held at each step: its index in ``bins``, −1 for a stop or a reverse."""
    h = np.arctan2(run.demo[:, 1], run.demo[:, 0])
    return np.where(run.informative, bins.index(h), -1)


def reading(ev: Evaluation) -> list[str]:
    """What the numbers mean, in plain sentences (the CLI prints them under the table)."""
    m = {k: v.heading_error_deg for k, v in ev.methods.items()}
    lines = []
    if ev.held_out_headings == 1:
        lines.append(
            "the held-out part is one constant command (every step the same heading): the scores"
            " mean little; hold out more (--holdout) or demonstrate more varied driving."
        )
    if not ev.turning_steps:
        lines.append("no held-out step turned (≥ 10° off ahead): there is no turn score.")
    if ev.keys is not None:
        lines.append(
            "a person at a keyboard: each fitted method's prediction is read as the key the person"
            " would press (its heading: the key whose bin holds the fused heading)."
        )
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
