"""The compiled loops of the ``pf`` sampler's likelihood (:mod:`lfdfuse.estimate.model`).

Each is a plain loop that numba compiles on first use (:mod:`lfdfuse.jit`); the numpy function
it stands for stays the reference (:func:`sum_cos_reference`,
:func:`~lfdfuse.estimate.model.log_marginal`), and the tests hold the two to 1e-12.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from lfdfuse.jit import kernel


class RowSteps(Protocol):
    """What the likelihood reads of a continuous row (:class:`~lfdfuse.estimate.model.RowData`)."""

    @property
    def along(self) -> np.ndarray: ...

    @property
    def across(self) -> np.ndarray: ...

    @property
    def steps(self) -> int: ...


#: elements of a (steps × particles) temporary when summing over a row: steps are taken in blocks
#: of this size over the particle count, so an hour-long demo or 30 trials cost the same memory
#: as a minute-long one
BLOCK_ELEMENTS = 1 << 21


def sum_cos_reference(data: RowSteps, w: np.ndarray) -> np.ndarray:
    """:func:`~lfdfuse.estimate.model.sum_cos` in numpy (one BLAS product per block of steps): the reference."""
    wt = np.ascontiguousarray(w.T)
    s = np.zeros(w.shape[0])
    block = max(16, BLOCK_ELEMENTS // max(1, w.shape[0]))
    for c in range(0, data.steps, block):
        a = data.along[c : c + block] @ wt
        b = data.across[c : c + block] @ wt
        # cos Δ = a / max(|(a, b)|, ε), in place: the same numbers, a third less time than temporaries
        np.hypot(a, b, out=b)
        np.maximum(b, 1e-12, out=b)
        np.divide(a, b, out=a)
        s += a.sum(axis=0)
    return s


def _sum_cos_loop(along: np.ndarray, across: np.ndarray, wt: np.ndarray, block: int) -> np.ndarray:
    """:func:`~lfdfuse.estimate.model.sum_cos` as one loop: ``along, across (T, n)``, ``wt (n, P)`` → ``S (P,)``, summed
    over blocks of ``block`` steps as the reference sums them (the particles innermost)."""
    steps, n = along.shape
    p_count = wt.shape[1]
    s = np.zeros(p_count)
    part = np.zeros(p_count)
    a = np.empty(p_count)
    b = np.empty(p_count)
    for c in range(0, steps, block):
        for t in range(c, min(steps, c + block)):
            x0 = along[t, 0]
            y0 = across[t, 0]
            for p in range(p_count):
                a[p] = x0 * wt[0, p]
                b[p] = y0 * wt[0, p]
            for k in range(1, n):
                x = along[t, k]
                y = across[t, k]
                for p in range(p_count):
                    a[p] += x * wt[k, p]
                    b[p] += y * wt[k, p]
            if t == c:
                for p in range(p_count):
                    part[p] = a[p] / max(math.sqrt(a[p] * a[p] + b[p] * b[p]), 1e-12)
            else:
                for p in range(p_count):
                    part[p] += a[p] / max(math.sqrt(a[p] * a[p] + b[p] * b[p]), 1e-12)
        for p in range(p_count):
            s[p] += part[p]
    return s


#: :func:`_sum_cos_loop`, compiled on first use
SUM_COS = kernel(_sum_cos_loop)


def _log_marginal_loop(s: np.ndarray, steps: float, kappas: np.ndarray, log_norm: np.ndarray) -> np.ndarray:
    """:func:`~lfdfuse.estimate.model.log_marginal` for ``S (P,)`` of rows of ``steps`` steps, as one loop."""
    j_count = len(kappas)
    out = np.empty(len(s))
    terms = np.empty(j_count)
    log_j = math.log(j_count)
    for p in range(len(s)):
        top = -np.inf
        for j in range(j_count):
            x = kappas[j] * (s[p] - steps) - steps * log_norm[j]
            terms[j] = x
            if x > top:
                top = x
        acc = 0.0
        for j in range(j_count):
            acc += math.exp(terms[j] - top)
        out[p] = top + math.log(acc) - log_j
    return out


#: :func:`_log_marginal_loop`, compiled on first use
LOG_MARGINAL = kernel(_log_marginal_loop)
