"""Round trips against a known fusion table: the quality check of estimation (DESIGN §6).

A known table drives the network teacher; the demonstration is segmented and estimated; the
learned table is compared with the truth per (step, BAC) — beside a least-squares heading fit on
the same steps and the Cramér–Rao bound — and by its heading error on a held-out demonstration
of the same teacher, against the error the true table itself has there (the noise floor).
Weights are those the runtime uses: the row's, else the step's default, else the table's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lfdfuse import learn
from lfdfuse.estimate.baselines import angle_errors, heading_fit_weights
from lfdfuse.estimate.replay import fused_vectors, runtime_weights
from lfdfuse.network.table import FusionTable, Step, leaf_steps, load_table
from lfdfuse.segment.read import SegmentedRun, read_segmented
from lfdfuse.world.model import load_world

#: hand-written sparse truth tables, ``<world>-<style>.yaml``
TRUTHS = Path(__file__).resolve().parent / "truths"
#: heading noise of the network teacher in round trips
TEACHER_NOISE_RAD = math.radians(5.0)


def truth_names() -> list[str]:
    """The shipped truth tables, by name (``tee-left``, …)."""
    return sorted(p.stem for p in TRUTHS.glob("*.yaml"))


def load_truth(name: str) -> tuple[FusionTable, str]:
    """A shipped truth table and the world it is written for (the name's first part)."""
    return load_table(TRUTHS / f"{name}.yaml"), name.split("-")[0]


@dataclass(frozen=True)
class Demo:
    """A demonstration of a truth table, segmented; ``simulate_s`` is the wall time to drive it."""

    run: SegmentedRun
    simulate_s: float


def demonstrate(
    truth: FusionTable,
    world: str,
    *,
    seed: int,
    duration_s: float,
    folder: Path,
    noise_rad: float = TEACHER_NOISE_RAD,
) -> Demo:
    """Drive the network teacher with ``truth`` (``simulate --teacher``), segment with its behaviours."""
    demo = learn.demonstrate(
        truth,
        world=load_world(world),
        folder=folder,
        name=f"{world}-{seed}",
        duration_s=duration_s,
        seed=seed,
        heading_noise_rad=noise_rad,
    )
    return Demo(read_segmented(demo.segmented), demo.wall_s)


def effective_weights(table: FusionTable, step: Step, bac: int) -> np.ndarray:
    """Runtime weights ``(K,)`` over ``table.behaviors`` restricted to the applicable behaviours
    and normalised to sum 1 (zeros when none of them carries weight)."""
    w = runtime_weights(table, step, bac)
    vec = np.array([w.get(n, 0.0) if bac >> i & 1 else 0.0 for i, n in enumerate(table.behaviors)])
    tot = vec.sum()
    return vec / tot if tot > 0 else vec


@dataclass(frozen=True)
class RowCompare:
    """One learned row beside the truth: weights over the applicable behaviours ``names``."""

    step: int
    bac: int
    samples: int
    names: tuple[str, ...]
    truth: np.ndarray
    estimate: np.ndarray
    fit: np.ndarray  # least-squares heading fit on the same steps
    crb: float  # Cramér–Rao bound on the L1 error at the truth
    identifiable: bool | None

    @property
    def l1(self) -> float:
        return float(np.abs(self.estimate - self.truth).sum())

    @property
    def fit_l1(self) -> float:
        return float(np.abs(self.fit - self.truth).sum())


def compare_rows(
    truth: FusionTable, learned: FusionTable, run: SegmentedRun, *, noise_rad: float, min_samples: int = 1
) -> list[RowCompare]:
    """Every learned row with ``min_samples`` steps of ``run`` (the training demo) beside the truth."""
    if truth.behaviors != learned.behaviors or run.names != truth.behaviors:
        raise ValueError("tables and run over different behaviour sets")
    out = []
    for i, (ts, ls) in enumerate(zip(leaf_steps(truth), leaf_steps(learned), strict=False)):
        seg = run.segments[i] if i < len(run.segments) else None
        if seg is None:
            break
        sl = np.arange(seg.start, seg.stop)
        for row in ls.fusion:
            steps = sl[(run.bac[sl] == row.bac) & run.informative[sl]]
            if len(steps) < min_samples:
                continue
            idx = [j for j in range(len(truth.behaviors)) if row.bac >> j & 1]
            vec, demo = run.vectors[steps][:, idx, :], run.demo[steps]
            tw = effective_weights(truth, ts, row.bac)[idx]
            lw = effective_weights(learned, ls, row.bac)[idx]
            out.append(
                RowCompare(
                    i,
                    row.bac,
                    len(steps),
                    tuple(truth.behaviors[j] for j in idx),
                    tw,
                    lw,
                    heading_fit_weights(vec, demo),
                    crb_l1(vec, tw, noise_rad),
                    row.identifiable,
                )
            )
    return out


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
    out = []
    for i, (ts, ls) in enumerate(zip(leaf_steps(truth), leaf_steps(learned), strict=False)):
        for row in ls.fusion:
            if (row.samples or 0) < min_samples:
                continue
            lw = effective_weights(learned, ls, row.bac)
            tw = effective_weights(truth, ts, row.bac)
            out.append(RowError(i, row.bac, row.samples or 0, float(np.abs(lw - tw).sum())))
    return out


def heading_errors(table: FusionTable, run: SegmentedRun) -> np.ndarray:
    """Per informative step of the run's goal segments the table has steps for: the fused heading
    error (rad), fused as the runtime fuses (:mod:`lfdfuse.evaluate.replay`)."""
    n_steps = len(leaf_steps(table))
    t = np.nonzero(run.informative & (run.segment_of < n_steps))[0]
    if len(t) == 0:
        return np.zeros(0)
    fused = fused_vectors(table, run, t)
    return angle_errors(fused[:, None, :], run.demo[t], np.ones(1))


def crb_l1(vectors: np.ndarray, weights: np.ndarray, noise_rad: float) -> float:
    """Cramér–Rao bound on the L1 error of normalised weights estimated from headings alone.

    ``vectors (T, n, 2)`` of one row's steps, the true normalised ``weights (n,)``, white heading
    noise of ``noise_rad``. The heading depends on the weights only up to scale, so the bound is
    taken on the simplex (weights summing to 1). Returns the sum of the per-weight standard
    deviations — about the expected L1 error of any unbiased estimator; ``inf`` when a direction
    is not identifiable at all.
    """
    n = len(weights)
    if n < 2:
        return 0.0
    f = np.einsum("tnd,n->td", vectors, weights)
    fn2 = f[:, 0] ** 2 + f[:, 1] ** 2
    jac = (f[:, None, 0] * vectors[:, :, 1] - f[:, None, 1] * vectors[:, :, 0]) / np.maximum(fn2, 1e-12)[
        :, None
    ]
    basis = np.linalg.svd(np.ones((1, n)))[2][1:].T  # (n, n−1): directions that keep the sum
    fisher = basis.T @ (jac.T @ jac) @ basis / noise_rad**2
    try:
        cov = basis @ np.linalg.inv(fisher) @ basis.T
    except np.linalg.LinAlgError:
        return float("inf")
    d = np.diag(cov)
    return float(np.sqrt(np.maximum(d, 0.0)).sum()) if np.all(np.isfinite(d)) else float("inf")
