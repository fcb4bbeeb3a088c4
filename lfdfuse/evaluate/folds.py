"""Blocked k-fold over a demo's informative decisions: ``evaluate``'s default split (DESIGN §12).

Holding out the last part of a drive by time scores nothing when the person stopped driving,
or reversed, near the end, and scores one key press when they held one. Here the demo's
*informative decisions* — for a discrete-command demo (a person at a keyboard) the decision
steps (:func:`~lfdfuse.estimate.commands.decision_steps`) that carry a heading, for a
continuous one every informative step — are cut into ``folds`` contiguous blocks of (nearly)
equal size. Fold ``j`` is the stretch of steps from its block's first decision to the next
block's (the first fold from step 0, the last to the end): the folds partition the steps, and
each holds ``1/folds`` of the decisions whatever the person did in between.

Every fold is scored by tables fitted on the others: the whole demo with the fold's steps made
uninformative, so the fit never sees them and every goal segment keeps its index. A method's
error is the mean over all held-out steps (each step scored once, by the fit that did not see
it), with a bootstrap interval over those steps; the mean of each fold's steps is kept beside
it (``fold_errors_deg``), their spread is what the printed ``± folds`` says. The methods are
:mod:`lfdfuse.evaluate.holdout`'s, read the same way per fold (the oracle fitted on the fold
itself, in the command set of the whole demo), plus ``bc``: behaviour cloning from the scan's
sector ranges (:mod:`lfdfuse.evaluate.cloning`), fitted on the same training steps. On a
discrete demo every fitted method's prediction (``bc``'s too) is read as a key press, its key
response fitted on the decisions of the steps it was fitted on (a fold's training steps; the
oracle's, the fold's own).

A demo with fewer than :data:`MIN_DECISIONS` informative decisions is not scored: a one-line
:class:`~lfdfuse.errors.ConfigError` says how many it has.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.commands import Commands, commands_of
from lfdfuse.estimate.keys import fit_key_response, key_heading
from lfdfuse.estimate.pipeline import EstimateOptions, Method, estimate_run
from lfdfuse.evaluate.cloning import clone_headings
from lfdfuse.evaluate.holdout import (
    TURN_RAD,
    Evaluation,
    MethodScore,
    _score,
    _wrap,
    command_of,
    keys_provenance,
    predict,
)
from lfdfuse.progress import Progress
from lfdfuse.progress import part as share
from lfdfuse.segment.read import SegmentedRun

FOLDS = 5
#: fewest informative decisions a demo is scored on (four per fold of five)
MIN_DECISIONS = 20
#: k-fold's methods, in the order they are shown: holdout's, with behaviour cloning beside the fits
KFOLD_METHODS: tuple[str, ...] = ("fused", "nnls", "arbitration", "bc", "straight", "previous", "oracle")
#: the fits of each fold: name, the estimator's method, fitted on the fold itself (the oracle)
_FITS: tuple[tuple[str, Method | None, bool], ...] = (
    ("fused", None, False),
    ("nnls", Method.NNLS, False),
    ("arbitration", Method.ARBITRATION, False),
    ("oracle", None, True),
)


def informative_decisions(run: SegmentedRun, cm: Commands) -> np.ndarray:
    """Step indices (sorted) of the decisions that carry a heading: the discrete model's
    informative decision steps, else every informative step."""
    if cm.decisions is None:
        return np.nonzero(run.informative)[0]
    return np.nonzero(cm.decisions & run.informative)[0]


def fold_ranges(decisions: np.ndarray, n_steps: int, folds: int) -> tuple[tuple[int, int], ...]:
    """``folds`` contiguous step ranges ``[start, stop)`` that partition ``range(n_steps)``, range
    ``j`` holding the ``j``-th of ``folds`` contiguous, nearly equal blocks of ``decisions``
    (sorted step indices; at least ``folds`` of them)."""
    if folds < 2:
        raise ConfigError(f"--folds must be at least 2, got {folds}")
    if len(decisions) < folds:
        raise ConfigError(f"{len(decisions)} decisions cannot fill {folds} folds")
    blocks = np.array_split(np.asarray(decisions, dtype=np.int64), folds)
    starts = [0, *(int(b[0]) for b in blocks[1:])]
    return tuple(zip(starts, [*starts[1:], n_steps], strict=True))


def too_few(n: int, *, need: int = MIN_DECISIONS) -> str:
    """The one line a demo with too few informative decisions gets."""
    return (
        f"too few decisions to score: {n} informative (steps where the person chose a heading), need {need};"
        " demonstrate longer"
    )


def evaluate_folds(
    run: SegmentedRun,
    *,
    folds: int = FOLDS,
    seed: int = 0,
    features: np.ndarray | None = None,
    opts: EstimateOptions | None = None,
    progress: Progress | None = None,
) -> Evaluation:
    """Score every method on every fold by fits on the other folds (see the module docstring).

    ``features (N, F)``: the scan features of each step for behaviour cloning
    (:func:`~lfdfuse.evaluate.cloning.sector_features`); without them there is no ``bc``.
    """
    base = opts or EstimateOptions(seed=seed)
    cm = commands_of(run, requested=base.commands, recheck_s=base.model.recheck_s)
    units = informative_decisions(run, cm)
    need = max(MIN_DECISIONS, folds)
    if len(units) < need:
        raise ConfigError(too_few(len(units), need=need))
    n = len(run.t_ns)
    ranges = fold_ranges(units, n, folds)
    truth = None if cm.bins is None else command_of(cm.bins, run)
    all_inf = np.nonzero(run.informative)[0]
    headings = np.arctan2(run.demo[all_inf, 1], run.demo[all_inf, 0])
    names = [m for m in KFOLD_METHODS if m != "bc" or features is not None]
    errors: dict[str, list[np.ndarray]] = {m: [] for m in names}
    chosen: dict[str, list[np.ndarray]] = {m: [] for m in names}
    actual: list[np.ndarray] = []
    demos: list[np.ndarray] = []
    train_sizes: list[int] = []
    responses: list[dict[str, object]] = []  # discrete: fused's key response of every fold
    for j, (a, b) in enumerate(ranges):
        fold = np.zeros(n, dtype=bool)
        fold[a:b] = True
        train = replace(run, informative=run.informative & ~fold)
        held = replace(run, informative=run.informative & fold)
        test_steps = np.nonzero(held.informative)[0]
        train_sizes.append(int(train.informative.sum()))
        demo = np.arctan2(run.demo[test_steps, 1], run.demo[test_steps, 0])
        demos.append(demo)
        decided = np.zeros(0, dtype=np.int64) if cm.decisions is None else np.nonzero(cm.decisions & fold)[0]
        predictions: dict[str, np.ndarray] = {}
        for k, (name, method, on_fold) in enumerate(_FITS):
            sub = share(progress, start=float(j * len(_FITS) + k), size=1.0, total=float(folds * len(_FITS)))
            eo = base if method is None else replace(base, method=method)
            part = held if on_fold else train
            try:
                table, _, _ = estimate_run(
                    part, opts=eo, name=name, progress=sub, command_set=cm.bins if on_fold else None
                )
            except ConfigError as exc:
                raise ConfigError(f"fold {j + 1} of {folds} (steps {a}–{b - 1}), {name}: {exc}") from exc
            predictions[name] = predict(table, run, test_steps)
            if cm.bins is not None and cm.decisions is not None and truth is not None:
                # a person at a keyboard: the key the fit predicts (its training decisions fit
                # the key response) and the heading of the key whose bin holds the prediction
                seen = np.nonzero(cm.decisions & part.informative)[0]
                response = fit_key_response(cm.bins, predict(table, run, seen), truth[seen], base.model)
                chosen[name].append(response.key(predict(table, run, decided), base.model))
                predictions[name] = key_heading(cm.bins, predictions[name])
                if name == "fused":
                    responses.append(response.provenance())
        predictions["straight"] = np.zeros(len(test_steps))
        where = np.searchsorted(all_inf, test_steps, side="left") - 1
        predictions["previous"] = np.where(where >= 0, headings[np.clip(where, 0, None)], 0.0)
        if features is not None:
            rows = np.nonzero(train.informative)[0]
            h_train = np.arctan2(run.demo[rows, 1], run.demo[rows, 0])
            predictions["bc"] = clone_headings(features[rows], h_train, features[test_steps])
            if cm.bins is not None and cm.decisions is not None and truth is not None:
                seen = np.nonzero(cm.decisions & train.informative)[0]
                at_seen = clone_headings(features[rows], h_train, features[seen])
                response = fit_key_response(cm.bins, at_seen, truth[seen], base.model)
                chosen["bc"].append(
                    response.key(clone_headings(features[rows], h_train, features[decided]), base.model)
                )
                predictions["bc"] = key_heading(cm.bins, predictions["bc"])
        for m in names:
            errors[m].append(_wrap(predictions[m] - demo))
        if cm.bins is not None and cm.decisions is not None and truth is not None:
            train_d = truth[cm.decisions & ~fold]
            values, counts = np.unique(train_d, return_counts=True)
            chosen["straight"].append(
                np.full(len(decided), values[int(np.argmax(counts))] if len(values) else -1)
            )
            chosen["previous"].append(truth[np.maximum(decided - 1, 0)])
            actual.append(truth[decided])
    rng = np.random.default_rng(seed)
    demo_all = np.concatenate(demos)
    turning = np.abs(demo_all) >= TURN_RAD
    scores: dict[str, MethodScore] = {}
    for m in names:
        s = _score(np.concatenate(errors[m]), turning, rng)
        per_fold = tuple(float(np.degrees(np.abs(e)).mean()) if len(e) else math.nan for e in errors[m])
        acc = None
        if actual:
            got = np.concatenate(actual)
            acc = float((np.concatenate(chosen[m]) == got).mean()) if len(got) else math.nan
        scores[m] = replace(s, command_accuracy=acc, fold_errors_deg=per_fold)
    lag = run.metadata.get("segment_lag_s")
    return Evaluation(
        train_steps=int(round(float(np.mean(train_sizes)))),
        test_steps=len(demo_all),
        turning_steps=int(turning.sum()),
        holdout=math.nan,
        lag_s=float(lag) if lag is not None else None,
        methods=scores,
        commands=cm.mode,
        test_decisions=None if not actual else int(sum(len(x) for x in actual)),
        held_out_headings=len(np.unique(np.round(np.degrees(demo_all), 1))),
        split="kfold",
        folds=folds,
        informative_decisions=len(units),
        keys=None if cm.bins is None else keys_provenance(responses),
    )


def reading_folds(ev: Evaluation) -> list[str]:
    """What k-fold adds to :func:`~lfdfuse.evaluate.holdout.reading`: behaviour cloning's verdict."""
    m = {k: v.heading_error_deg for k, v in ev.methods.items()}
    if "bc" not in m or not math.isfinite(m["bc"]):
        return []
    if m["bc"] < m["fused"]:
        return [
            f"behaviour cloning from the scan's sectors (bc, {m['bc']:.1f}°) beats fused ({m['fused']:.1f}°)"
            " on the same training steps: the data holds more than these primitives express."
        ]
    return [
        f"fused ({m['fused']:.1f}°) beats behaviour cloning from the scan's sectors (bc, {m['bc']:.1f}°)"
        " on the same training steps: the primitives carry what this much data can teach."
    ]
