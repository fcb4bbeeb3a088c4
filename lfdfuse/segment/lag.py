"""Which command lag explains a demonstration best (a cheap diagnostic for ``segment``).

Teachers and people react late: the command issued ``lag`` after a scan often explains that
scan better than the command in force at it. For each candidate lag, every BAC group of the
demo gets a non-negative least-squares fusion of its applicable behaviours' vectors to the
demonstrated unit vectors; the lag with the smallest mean heading error of those fits wins.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from lfdfuse.behaviors.primitives import BehaviorOutputs
from lfdfuse.control.drive import DriveParams
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
