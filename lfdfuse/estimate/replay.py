"""Replaying a fusion table over a segmented log: the fused vector the runtime would steer by.

Used where a learned table is compared with the demonstration: decision points for sub-goals
(:mod:`lfdfuse.estimate.subgoals`), round trips and held-out prediction (:mod:`lfdfuse.evaluate`).

The weights are those execute uses (DESIGN §8): the step's row for the BAC, else the step's
default weights, else the table's; where a row's fused vector is zero, the fallback's. The
table's network step ``i`` serves the log's goal segment ``i + segment_offset``; a segment the
table has no step for uses the table's default weights.
"""

from __future__ import annotations

import numpy as np

from lfdfuse.network.table import FusionTable, Step, leaf_steps
from lfdfuse.segment.read import SegmentedRun


def runtime_weights(table: FusionTable, step: Step | None, bac: int) -> dict[str, float]:
    """The weights execute uses in a BAC: the row's, else the step's default, else the table's."""
    if step is None:
        return table.default_weights
    row = step.row(bac)
    if row is not None:
        return row.weights
    return fallback_weights(table, step)


def fallback_weights(table: FusionTable, step: Step | None) -> dict[str, float]:
    if step is not None and step.default_weights is not None:
        return step.default_weights
    return table.default_weights


def fused_vectors(
    table: FusionTable, run: SegmentedRun, steps: np.ndarray, *, segment_offset: int = 0
) -> np.ndarray:
    """Fused vectors ``(T, 2)`` of the table at the log's ``steps`` (indices into the run)."""
    leaf = leaf_steps(table)
    names = table.behaviors
    pos = [run.names.index(n) for n in names]
    vec = run.vectors[steps][:, pos, :]  # (T, K, 2)
    w = np.zeros((len(steps), len(names)))
    fb = np.zeros((len(steps), len(names)))
    keys = np.stack([run.segment_of[steps] - segment_offset, run.bac[steps]], axis=1)
    for i, bac in {(int(a), int(b)) for a, b in keys.tolist()}:
        step = leaf[i] if 0 <= i < len(leaf) else None
        sel = (keys[:, 0] == i) & (keys[:, 1] == bac)
        rw, fw = runtime_weights(table, step, bac), fallback_weights(table, step)
        w[sel] = [rw.get(n, 0.0) for n in names]
        fb[sel] = [fw.get(n, 0.0) for n in names]
    fused = np.einsum("tkd,tk->td", vec, w)
    zero = np.hypot(fused[:, 0], fused[:, 1]) <= 1e-9
    if zero.any():
        fused[zero] = np.einsum("tkd,tk->td", vec[zero], fb[zero])
    return np.asarray(fused)
