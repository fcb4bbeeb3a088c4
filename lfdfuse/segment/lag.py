"""Which command lag explains a demonstration best (a cheap diagnostic for ``segment``).

Teachers and people react late: the command issued ``lag`` after a scan often explains that
scan better than the command in force at it. For each candidate lag, every BAC group of the
demo gets a non-negative least-squares fusion of its applicable behaviours' vectors to the
demonstrated unit vectors; the lag with the smallest mean heading error of those fits wins.
For a discrete demo (a person at a keyboard) a held command is as old as its press: over all
ticks the best lag is the reaction plus the typical age of the held key, while a decision (a
press) answers the scene one reaction earlier. :func:`press_lag_fits` fits the weights once, over
every tick at the best tick lag, and scores the presses alone at each candidate lag.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from lfdfuse.behaviors.primitives import BehaviorOutputs
from lfdfuse.control.command import DriveParams
from lfdfuse.log.reader import Run
from lfdfuse.segment.demo import demonstrated

#: candidate lags in seconds (teachers react within about a second)
CANDIDATE_LAGS_S: tuple[float, ...] = tuple(round(0.1 * k, 1) for k in range(0, 11))


@dataclass(frozen=True)
class LagFit:
    lag_s: float
    heading_error_deg: float  # mean absolute heading error of per-BAC nnls fits
    steps: int  # informative steps that entered the fits


def fit_error_deg(vectors: np.ndarray, demo: np.ndarray, bac: np.ndarray) -> tuple[float, int]:
    """Mean absolute heading error (deg) of per-BAC nnls fits: ``vectors (N, K, 2)``, ``demo (N, 2)``."""
    errors: list[np.ndarray] = []
    for b in np.unique(bac):
        rows = np.nonzero(bac == b)[0]
        cols = [j for j in range(vectors.shape[1]) if int(b) >> j & 1]
        if not cols or len(rows) < 2:
            continue
        v = vectors[rows][:, cols, :]  # (T, n, 2)
        a = v.transpose(0, 2, 1).reshape(-1, len(cols))  # x and y rows stacked
        w, _ = nnls(a, demo[rows].reshape(-1))
        fused = np.einsum("tnc,n->tc", v, w)
        err = np.arctan2(
            fused[:, 0] * demo[rows, 1] - fused[:, 1] * demo[rows, 0],
            fused[:, 0] * demo[rows, 0] + fused[:, 1] * demo[rows, 1],
        )
        # a zero fused vector (nnls found no non-negative fit) has no heading: arctan2 of signed
        # zeros would call it 0° or 180° at random; count it as 90°, a random heading's mean error
        zero = (fused[:, 0] == 0) & (fused[:, 1] == 0)
        errors.append(np.where(zero, np.pi / 2, np.abs(err)))
    if not errors:
        return float("nan"), 0
    allerr = np.concatenate(errors)
    return float(np.degrees(allerr.mean())), len(allerr)


def press_steps(vr: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Steps where the held command changes (a press): where a person decided."""
    out = np.ones(len(vr), dtype=bool)
    if len(vr) > 1:
        out[1:] = (ok[1:] != ok[:-1]) | (np.abs(vr[1:] - vr[:-1]).max(axis=1) > 1e-9)
    return out


def lag_fits(
    run: Run, outputs: BehaviorOutputs, drive: DriveParams, lags_s: tuple[float, ...] = CANDIDATE_LAGS_S
) -> list[LagFit]:
    """The fit error of every candidate lag, in the order given."""
    out = []
    for lag in lags_s:
        vr, ok = demonstrated(run, drive, lag_ns=int(round(lag * 1e9)))
        err, n = fit_error_deg(outputs.vectors[ok], vr[ok], outputs.bac[ok])
        out.append(LagFit(lag, err, n))
    return out


def best_fit(fits: tuple[LagFit, ...] | list[LagFit]) -> LagFit | None:
    """The fit whose lag explains the demo best (the smallest lag among equals), or None when
    no fit had informative steps."""
    ok = [f for f in fits if f.steps > 0 and f.heading_error_deg == f.heading_error_deg]
    return min(ok, key=lambda f: (round(f.heading_error_deg, 9), f.lag_s)) if ok else None


def best_lag(fits: tuple[LagFit, ...] | list[LagFit]) -> float:
    """The lag of :func:`best_fit`; 0 without fits."""
    best = best_fit(fits)
    return 0.0 if best is None else best.lag_s


#: fewer presses than this cannot place a lag: the tick lag stands
MIN_PRESSES = 30


def press_lag_fits(
    run: Run,
    outputs: BehaviorOutputs,
    drive: DriveParams,
    fit_lag_s: float,
    lags_s: tuple[float, ...] = CANDIDATE_LAGS_S,
) -> list[LagFit]:
    """Per candidate lag, the mean heading error at the presses of per-BAC nnls weights fitted
    over every tick at ``fit_lag_s``, smoothed over neighbouring lags (a 3-point mean: the presses
    are few, and neighbouring lags pair them with nearly the same scans)."""
    vr, ok = demonstrated(run, drive, lag_ns=int(round(fit_lag_s * 1e9)))
    weights: dict[int, np.ndarray] = {}
    k = outputs.vectors.shape[1]
    for b in np.unique(outputs.bac[ok]):
        rows = np.nonzero(ok & (outputs.bac == b))[0]
        cols = [j for j in range(k) if int(b) >> j & 1]
        if not cols or len(rows) < 2:
            continue
        v = outputs.vectors[rows][:, cols, :]
        w, _ = nnls(v.transpose(0, 2, 1).reshape(-1, len(cols)), vr[rows].reshape(-1))
        full = np.zeros(k)
        full[cols] = w
        weights[int(b)] = full
    raw: list[tuple[float, int]] = []
    for lag in lags_s:
        d, okl = demonstrated(run, drive, lag_ns=int(round(lag * 1e9)))
        steps = np.nonzero(press_steps(d, okl) & okl & np.isin(outputs.bac, list(weights)))[0]
        if len(steps) == 0:
            raw.append((float("nan"), 0))
            continue
        w = np.stack([weights[int(b)] for b in outputs.bac[steps]])  # (P, K)
        fused = np.einsum("pk,pkc->pc", w, outputs.vectors[steps])
        dd = d[steps]
        err = np.arctan2(fused[:, 0] * dd[:, 1] - fused[:, 1] * dd[:, 0], (fused * dd).sum(axis=1))
        raw.append((float(np.degrees(np.abs(err).mean())), len(steps)))
    errs = np.array([e for e, _ in raw])
    out = []
    for i, lag in enumerate(lags_s):
        near = errs[max(0, i - 1) : i + 2]
        out.append(
            LagFit(lag, float(np.nanmean(near)) if np.isfinite(near).any() else float("nan"), raw[i][1])
        )
    return out
