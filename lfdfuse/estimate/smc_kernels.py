"""The compiled steps of the ``pf`` sampler (:mod:`lfdfuse.estimate.smc`) besides the likelihood.

A Metropolis move over every chain at once — in numpy a dozen passes over ``(chains, particles,
behaviours)`` arrays — is two loops around numpy's Cholesky factor (:data:`MOVE_FRAME`,
:data:`MOVE_PROPOSE`); the adaptive temperature step (an ESS bisection, 31 numpy passes over
``(chains, particles)``) is one (:data:`NEXT_DELTA`). Every sum is taken in the order numpy takes
it on x86-64 (its pairwise reductions, the two-lane loop of its ``einsum``), so there the compiled
steps give the bits of their numpy references (:func:`move_frame_reference`,
:func:`move_propose_reference`, :func:`next_delta_reference`): the sampler's path is chaotic, one
ulp is another draw. The tests hold them to 1e-12 everywhere and to the bit on x86-64.
"""

from __future__ import annotations

import math

import numpy as np

from lfdfuse.estimate.kernels import _logsumexp_rows_loop, logsumexp_last
from lfdfuse.estimate.resampling import ess
from lfdfuse.kernels.jit import kernel
from lfdfuse.kernels.pairwise import STACK, pairwise_sum


def move_frame_reference(logw: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The frame of a move: for log-weights ``logw (C, M, n)`` over the behaviours ``mask (C, n)``,
    each chain's heaviest behaviour ``ref (C,)`` (the additive-log-ratio denominator), the
    particles in those coordinates ``y (C, M, n)`` (0 at ``ref`` and on padding) and their
    covariance ``(C, n, n)`` (a ``1e-8`` ridge on the diagonal)."""
    c, m, n = logw.shape
    mean_w = np.where(mask, np.exp(logw).mean(axis=1), -1.0)
    ref = np.argmax(mean_w, axis=1)
    lref = np.take_along_axis(logw, ref[:, None, None], axis=2)
    y = np.where(mask[:, None, :], logw - lref, 0.0)
    d = y - y.mean(axis=1, keepdims=True)
    cov = np.einsum("cmi,cmj->cij", d, d) / max(1, m - 1) + 1e-8 * np.eye(n)
    return np.asarray(ref), np.asarray(y), np.asarray(cov)


def move_propose_reference(
    y: np.ndarray,
    logw: np.ndarray,
    mask: np.ndarray,
    ref: np.ndarray,
    chol: np.ndarray,
    z: np.ndarray,
    scale: np.ndarray,
    alpha: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The proposal of a move: ``y + scale · chol z`` on the free coordinates (not ``ref``, not
    padding) back to log-weights ``(C, M, n)``, with the log prior (Dirichlet ``alpha`` in these
    coordinates, :func:`~lfdfuse.estimate.model.log_prior_alr`) of the particles ``(C, M)`` and of
    the proposals ``(C, M)``."""
    c = logw.shape[0]
    mask3 = mask[:, None, :]
    free = mask.copy()
    free[np.arange(c), ref] = False
    step = np.einsum("cij,cmj->cmi", chol, z) * scale[:, None, None]
    y_new = np.where(free[:, None, :], y + step, np.where(mask3, y, -np.inf))
    logw_new = y_new - logsumexp_last(y_new, keepdims=True)
    prior = alpha * np.where(mask3, logw, 0.0).sum(axis=-1)
    prior_new = alpha * np.where(mask3, logw_new, 0.0).sum(axis=-1)
    return np.asarray(logw_new), np.asarray(prior), np.asarray(prior_new)


def _move_frame_loop(
    logw: np.ndarray, mask: np.ndarray, active: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`move_frame_reference` for the ``active (C,)`` chains (the others: ``ref`` 0, ``y``
    0 and the identity covariance)."""
    c_count, m, n = logw.shape
    ref = np.zeros(c_count, dtype=np.int64)
    y = np.zeros((c_count, m, n))
    cov = np.zeros((c_count, n, n))
    mean = np.empty(n)
    for c in range(c_count):
        if not active[c]:
            for i in range(n):
                cov[c, i, i] = 1.0
            continue
        for i in range(n):
            mean[i] = 0.0
        for p in range(m):
            for i in range(n):
                mean[i] += math.exp(logw[c, p, i])
        best = 0
        top = -np.inf
        for i in range(n):
            v = mean[i] / m if mask[c, i] else -1.0
            if v > top or (i == 0):
                top = v
                best = i
        ref[c] = best
        for i in range(n):
            mean[i] = 0.0
        for p in range(m):
            lref = logw[c, p, best]
            for i in range(n):
                v = logw[c, p, i] - lref if mask[c, i] else 0.0
                y[c, p, i] = v
                mean[i] += v
        for i in range(n):
            mean[i] = mean[i] / m
        for p in range(m):
            for i in range(n):
                di = y[c, p, i] - mean[i]
                for j in range(n):
                    cov[c, i, j] += di * (y[c, p, j] - mean[j])
        div = max(1, m - 1)
        for i in range(n):
            for j in range(n):
                cov[c, i, j] = cov[c, i, j] / div + (1e-8 if i == j else 0.0)
    return ref, y, cov


#: :func:`_move_frame_loop`, compiled on first use
MOVE_FRAME = kernel(_move_frame_loop)


def _move_propose_loop(
    y: np.ndarray,
    logw: np.ndarray,
    mask: np.ndarray,
    ref: np.ndarray,
    chol: np.ndarray,
    z: np.ndarray,
    scale: np.ndarray,
    alpha: float,
    active: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`move_propose_reference` for the ``active (C,)`` chains (the others keep their
    log-weights, both priors theirs). ``chol z`` is summed as numpy's ``einsum`` sums it on
    x86-64: two running sums over alternate behaviours (its loop of eight taken last pair
    first), added at the end."""
    c_count, m, n = logw.shape
    logw_new = logw.copy()
    prior = np.zeros((c_count, m))
    prior_new = np.zeros((c_count, m))
    row = np.empty(n)
    stack_lo = np.empty(STACK, dtype=np.int64)
    stack_n = np.empty(STACK, dtype=np.int64)
    stack_st = np.empty(STACK, dtype=np.int64)
    vals = np.empty(STACK)
    for c in range(c_count):
        r = ref[c]
        for p in range(m):
            for i in range(n):
                row[i] = logw[c, p, i] if mask[c, i] else 0.0
            prior[c, p] = alpha * pairwise_sum(row, n, stack_lo, stack_n, stack_st, vals)
        if not active[c]:
            for p in range(m):
                prior_new[c, p] = prior[c, p]
            continue
        y_new = np.empty((m, n))
        for p in range(m):
            for i in range(n):
                if mask[c, i] and i != r:
                    lane0 = 0.0
                    lane1 = 0.0
                    j = 0
                    while n - j >= 8:  # numpy's unrolled loop: four pairs, the last first
                        for q in range(6, -1, -2):
                            lane0 += chol[c, i, j + q] * z[c, p, j + q]
                            lane1 += chol[c, i, j + q + 1] * z[c, p, j + q + 1]
                        j += 8
                    while j + 1 < n:
                        lane0 += chol[c, i, j] * z[c, p, j]
                        lane1 += chol[c, i, j + 1] * z[c, p, j + 1]
                        j += 2
                    if j < n:
                        lane0 += chol[c, i, j] * z[c, p, j]
                        lane1 += 0.0
                    y_new[p, i] = y[c, p, i] + (0.0 + (lane0 + lane1)) * scale[c]
                elif mask[c, i]:
                    y_new[p, i] = y[c, p, i]
                else:
                    y_new[p, i] = -np.inf
        lse = _logsumexp_rows_loop(y_new)
        for p in range(m):
            for i in range(n):
                v = y_new[p, i] - lse[p]
                logw_new[c, p, i] = v
                row[i] = v if mask[c, i] else 0.0
            prior_new[c, p] = alpha * pairwise_sum(row, n, stack_lo, stack_n, stack_st, vals)
    return logw_new, prior, prior_new


#: :func:`_move_propose_loop`, compiled on first use
MOVE_PROPOSE = kernel(_move_propose_loop, calls=[pairwise_sum, _logsumexp_rows_loop])


def next_delta_reference(ll: np.ndarray, room: np.ndarray, target: float) -> np.ndarray:
    """Per chain the temperature increment ``(C,)`` that brings the effective sample size of the
    incremental weights ``L^δ`` to ``target``, ``δ`` at most ``room (C,)``: all of it when that
    keeps the ESS at the target, else 30 bisections (and never below ``min(room, 1e-6)``: a
    chain whose every step collapses still advances). ``ll (C, M)``: the particles' log-likelihoods."""
    ok = ess(room[:, None] * ll) >= target
    lo = np.zeros_like(room)
    top = room.copy()
    for _ in range(30):
        mid = 0.5 * (lo + top)
        good = ess(mid[:, None] * ll) >= target
        lo = np.where(good, mid, lo)
        top = np.where(good, top, mid)
    return np.asarray(np.where(ok, room, np.maximum(lo, np.minimum(room, 1e-6))))


def _next_delta_loop(ll: np.ndarray, room: np.ndarray, target: float) -> np.ndarray:
    """:func:`next_delta_reference` as one loop per chain, each effective sample size computed
    operation for operation as :func:`~lfdfuse.estimate.resampling.ess` computes it on x86-64:
    numpy's pairwise sum of the weights (halves cut at a multiple of 8 down to leaves of at most
    128, each summed in eight running sums) and its ``einsum``'s sum of squares (two lanes, eight
    at a time last pair first)."""
    c_count, m = ll.shape
    out = np.empty(c_count)
    w = np.empty(max(m, 1))
    stack_lo = np.empty(STACK, dtype=np.int64)
    stack_n = np.empty(STACK, dtype=np.int64)
    stack_st = np.empty(STACK, dtype=np.int64)
    vals = np.empty(STACK)
    for c in range(c_count):
        hi = room[c]
        lo = 0.0
        top_x = hi
        out[c] = hi
        for it in range(31):
            x_scale = hi if it == 0 else 0.5 * (lo + top_x)
            # the weights exp(x - max), normalised
            top = -np.inf
            nan = False
            for p in range(m):
                x = x_scale * ll[c, p]
                w[p] = x
                if x != x:
                    nan = True
                elif x > top:
                    top = x
            if nan:
                top = np.nan
            shift = top if (top - top) == 0.0 else 0.0  # np.where(isfinite(top), top, 0)
            for p in range(m):
                w[p] = math.exp(w[p] - shift)
            total = pairwise_sum(w, m, stack_lo, stack_n, stack_st, vals)
            for p in range(m):
                w[p] = w[p] / total
            lane0 = 0.0
            lane1 = 0.0
            j = 0
            while m - j >= 8:
                for q in range(6, -1, -2):
                    lane0 += w[j + q] * w[j + q]
                    lane1 += w[j + q + 1] * w[j + q + 1]
                j += 8
            while j + 1 < m:
                lane0 += w[j] * w[j]
                lane1 += w[j + 1] * w[j + 1]
                j += 2
            if j < m:
                lane0 += w[j] * w[j]
                lane1 += 0.0
            good = 1.0 / (0.0 + (lane0 + lane1)) >= target
            if it == 0:
                if good:
                    break
            elif good:
                lo = x_scale
            else:
                top_x = x_scale
        else:
            out[c] = max(lo, min(hi, 1e-6))
    return out


#: :func:`_next_delta_loop`, compiled on first use
NEXT_DELTA = kernel(_next_delta_loop, calls=[pairwise_sum])
