"""Round trips against a known fusion table: the quality check of estimation (DESIGN §6).

A known table drives the network teacher; the demonstration is segmented and estimated; the
learned table is compared with the truth per (step, BAC) and by its heading error on a held-out
demonstration of the same teacher, against the error the true table itself has there (the noise
floor).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lfdfuse.estimate.baselines import angle_errors
from lfdfuse.network.table import FusionTable, Step
from lfdfuse.segment.read import SegmentedRun


def leaf_steps(table: FusionTable) -> list[Step]:
    out: list[Step] = []

    def walk(steps: tuple[Step, ...]) -> None:
        for s in steps:
            if s.network is not None:
                walk(s.network.steps)
            else:
                out.append(s)

    walk(table.network.steps)
    return out


def effective_weights(table: FusionTable, step: Step, bac: int) -> np.ndarray:
    """Weights ``(K,)`` over ``table.behaviors`` that the runtime uses in a BAC (row or default),
    restricted to the applicable behaviours and normalised to sum 1."""
    row = step.row(bac)
    w = row.weights if row is not None else table.default_weights
    names = table.behaviors
    vec = np.array([w.get(n, 0.0) if bac >> i & 1 else 0.0 for i, n in enumerate(names)])
    tot = vec.sum()
    return vec / tot if tot > 0 else vec


@dataclass(frozen=True)
class RowError:
    step: int
    bac: int
    samples: int
    l1: float


def weight_errors(truth: FusionTable, learned: FusionTable, *, min_samples: int = 50) -> list[RowError]:
    """L1 between learned rows and the true effective weights, for rows with enough samples."""
    if truth.behaviors != learned.behaviors:
        raise ValueError("tables over different behaviour sets")
    t_steps, l_steps = leaf_steps(truth), leaf_steps(learned)
    out = []
    for i, (ts, ls) in enumerate(zip(t_steps, l_steps, strict=False)):
        for row in ls.fusion:
            if (row.samples or 0) < min_samples:
                continue
            lw = effective_weights(learned, ls, row.bac)
            tw = effective_weights(truth, ts, row.bac)
            out.append(RowError(i, row.bac, row.samples or 0, float(np.abs(lw - tw).sum())))
    return out


def heading_errors(table: FusionTable, run: SegmentedRun) -> np.ndarray:
    """Per informative step of a segmented run: the table's fused heading error (rad)."""
    steps = leaf_steps(table)
    errs = []
    for seg in run.segments:
        if seg.index >= len(steps):
            break
        step = steps[seg.index]
        for t in range(seg.start, seg.stop):
            if not run.informative[t]:
                continue
            w = effective_weights(table, step, int(run.bac[t]))
            errs.append(angle_errors(run.vectors[t : t + 1], run.demo[t : t + 1], w)[0])
    return np.array(errs)


def crb_l1(vectors: np.ndarray, weights: np.ndarray, noise_rad: float) -> float:
    """Cramér–Rao bound on the L1 error of normalised weights estimated from headings alone.

    ``vectors (T, n, 2)`` of one row's steps, the true normalised ``weights (n,)``, white heading
    noise of ``noise_rad``. The heading depends on the weights only up to scale, so the bound is
    taken on the simplex (weights summing to 1). Returns the sum of the per-weight standard
    deviations — about the expected L1 error of any unbiased estimator; ``inf`` when a direction
    is not identifiable at all.
    """
    f = np.einsum("tnd,n->td", vectors, weights)
    fn2 = f[:, 0] ** 2 + f[:, 1] ** 2
    jac = (f[:, None, 0] * vectors[:, :, 1] - f[:, None, 1] * vectors[:, :, 0]) / np.maximum(fn2, 1e-12)[
        :, None
    ]
    n = len(weights)
    if n < 2:
        return 0.0
    basis = np.linalg.svd(np.ones((1, n)))[2][1:].T  # (n, n−1): directions that keep the sum
    fisher = basis.T @ (jac.T @ jac) @ basis / noise_rad**2
    try:
        cov = basis @ np.linalg.inv(fisher) @ basis.T
    except np.linalg.LinAlgError:
        return float("inf")
    d = np.diag(cov)
    return float(np.sqrt(np.maximum(d, 0.0)).sum()) if np.all(np.isfinite(d)) else float("inf")
