"""The compiled loops of the ``pf`` sampler's likelihood (:mod:`lfdfuse.estimate.model`).

Each is a plain loop that numba compiles on first use (:mod:`lfdfuse.jit`); the numpy function
it stands for stays the reference (:func:`sum_cos_reference`,
:func:`~lfdfuse.estimate.model.log_marginal`), and the tests hold the two to 1e-12.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
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


def _sum_cos_loop(
    along: np.ndarray, across: np.ndarray, wt: np.ndarray, block: int, width: tuple[int, ...]
) -> np.ndarray:
    """:func:`~lfdfuse.estimate.model.sum_cos` as one loop: ``along, across (T, n)``, ``wt (n, P)`` → ``S (P,)``, summed
    over blocks of ``block`` steps as the reference sums them (the particles innermost).

    ``width``: any tuple of ``n`` items (:func:`behaviour_width`). Its length is a constant of the
    compiled code, one specialisation per ``n``: the loop over the behaviours unrolls, each
    particle's two dot products stay in registers and the particles run in vector lanes (half
    again as fast as a loop over ``n`` known only at run time). Each particle's sums are taken
    in the same order either way: the same numbers."""
    steps = along.shape[0]
    n = len(width)
    p_count = wt.shape[1]
    s = np.zeros(p_count)
    part = np.zeros(p_count)
    for c in range(0, steps, block):
        for t in range(c, min(steps, c + block)):
            first = t == c
            for p in range(p_count):
                a = along[t, 0] * wt[0, p]
                b = across[t, 0] * wt[0, p]
                for k in range(1, n):
                    a += along[t, k] * wt[k, p]
                    b += across[t, k] * wt[k, p]
                v = a / max(math.sqrt(a * a + b * b), 1e-12)
                part[p] = v if first else part[p] + v
        for p in range(p_count):
            s[p] += part[p]
    return s


def behaviour_width(n: int) -> tuple[int, ...]:
    """The ``width`` argument of :func:`_sum_cos_loop` for rows of ``n`` behaviours."""
    return (0,) * n


#: :func:`_sum_cos_loop`, compiled on first use
SUM_COS = kernel(_sum_cos_loop, specialise_on=4)

#: particle-steps below which a row's likelihood runs in one thread (a thread's hand-over costs
#: about what a few hundred thousand particle-steps do)
SPLIT_WORK = 1 << 18

_pool: list[ThreadPoolExecutor] = []


def _cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _forget_pool() -> None:
    _pool.clear()  # a forked child has none of its parent's threads


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool)


def continuous_loglik(
    along: np.ndarray,
    across: np.ndarray,
    wt: np.ndarray,
    block: int,
    steps: float,
    kappas: np.ndarray,
    log_norm: np.ndarray,
) -> np.ndarray:
    """``log p(data | w)`` of a continuous row for weights ``wt (n, P)`` (:data:`SUM_COS` then
    :data:`LOG_MARGINAL`), the particles shared out over the machine's cores when the row is
    long enough to pay for it. Each particle's numbers are computed on their own, in the same
    order, whichever thread and share it falls in: the result does not depend on the split."""
    n, p_count = wt.shape
    width = behaviour_width(n)

    def one(w: np.ndarray) -> np.ndarray:
        return np.asarray(LOG_MARGINAL(SUM_COS(along, across, w, block, width), steps, kappas, log_norm))

    cores = _cores()
    parts = min(cores, p_count // 64, (along.shape[0] * p_count) // SPLIT_WORK)
    if parts < 2 or not (SUM_COS.warm_for(n) and LOG_MARGINAL.warm_for()):
        return one(wt)
    if not _pool:
        _pool.append(ThreadPoolExecutor(max_workers=cores - 1, thread_name_prefix="lfdfuse-pf"))
    cuts = [p_count * i // parts for i in range(parts + 1)]
    chunks = [np.ascontiguousarray(wt[:, lo:hi]) for lo, hi in zip(cuts[:-1], cuts[1:], strict=True)]
    futures = [_pool[0].submit(one, w) for w in chunks[1:]]
    first = one(chunks[0])  # this thread takes a share too
    return np.concatenate([first, *(f.result() for f in futures)])


#: ``math.exp(x) == 0.0`` for every ``x`` below this (the smallest subnormal is ``exp(-744.4)``)
_EXP_ZERO = -750.0


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
            d = terms[j] - top
            # exp of anything below -745.2 is +0.0, and adding +0.0 leaves the sum as it is: the
            # nodes far from the peak (most of them, on a long row) cost no exp (NaN still adds)
            if not d < _EXP_ZERO:
                acc += math.exp(d)
        out[p] = top + math.log(acc) - log_j
    return out


#: :func:`_log_marginal_loop`, compiled on first use
LOG_MARGINAL = kernel(_log_marginal_loop)


def _logsumexp_rows_loop(a: np.ndarray) -> np.ndarray:
    """``scipy.special.logsumexp(a, axis=-1)`` of rows ``a (R, L)`` (real, no ``b``), operation for
    operation as scipy 1.17 computes it: the maximum's terms counted apart (``log1p`` of the
    rest's sum over their count, plus the log of the count), the sum over a row numpy's pairwise
    sum, and where that is not finite the plain ``log(Σ exp a)``."""
    rows, length = a.shape
    out = np.empty(rows)
    buf = np.empty(max(length, 1))
    stack_lo = np.empty(64, dtype=np.int64)
    stack_n = np.empty(64, dtype=np.int64)
    stack_st = np.empty(64, dtype=np.int64)
    vals = np.empty(64)
    sums = np.zeros(2)
    for i in range(rows):
        top = -np.inf
        nan = False
        for j in range(length):
            x = a[i, j]
            if x != x:
                nan = True
            elif x > top:
                top = x
        if nan:
            top = np.nan
        count = 0.0
        for j in range(length):
            count += 1.0 if a[i, j] == top else 0.0
        for pass_ in range(2):
            for j in range(length):
                x = a[i, j]
                if pass_ == 0:
                    buf[j] = math.exp((-np.inf if x == top else x) - top)
                else:
                    buf[j] = math.exp(x)
            # numpy's pairwise sum of buf[:length] (post-order over its split tree)
            vp = 0
            stack_lo[0] = 0
            stack_n[0] = length
            stack_st[0] = 0
            sp = 1
            while sp > 0:
                lo = stack_lo[sp - 1]
                cnt = stack_n[sp - 1]
                if cnt <= 128:
                    sp -= 1
                    if cnt < 8:
                        res = 0.0
                        for k in range(cnt):
                            res += buf[lo + k]
                    else:
                        a0 = buf[lo]
                        a1 = buf[lo + 1]
                        a2 = buf[lo + 2]
                        a3 = buf[lo + 3]
                        a4 = buf[lo + 4]
                        a5 = buf[lo + 5]
                        a6 = buf[lo + 6]
                        a7 = buf[lo + 7]
                        k = 8
                        stop = cnt - cnt % 8
                        while k < stop:
                            a0 += buf[lo + k]
                            a1 += buf[lo + k + 1]
                            a2 += buf[lo + k + 2]
                            a3 += buf[lo + k + 3]
                            a4 += buf[lo + k + 4]
                            a5 += buf[lo + k + 5]
                            a6 += buf[lo + k + 6]
                            a7 += buf[lo + k + 7]
                            k += 8
                        res = ((a0 + a1) + (a2 + a3)) + ((a4 + a5) + (a6 + a7))
                        while k < cnt:
                            res += buf[lo + k]
                            k += 1
                    vals[vp] = res
                    vp += 1
                elif stack_st[sp - 1] == 0:
                    stack_st[sp - 1] = 1
                    half = cnt // 2
                    half -= half % 8
                    stack_lo[sp] = lo + half
                    stack_n[sp] = cnt - half
                    stack_st[sp] = 0
                    stack_lo[sp + 1] = lo
                    stack_n[sp + 1] = half
                    stack_st[sp + 1] = 0
                    sp += 2
                else:
                    sp -= 1
                    vals[vp - 2] = vals[vp - 2] + vals[vp - 1]
                    vp -= 1
            sums[pass_] = 0.0 + vals[0]
            if pass_ == 0:
                s = sums[0]
                s = s if s == 0 else s / count
                sgn = np.sign(s + 1.0) * np.sign(count)
                if s < -1.0:
                    s = -s - 2.0
                r = math.log1p(s) + math.log(abs(count)) + top
                if sgn < 0:
                    r = np.nan
                if np.isfinite(r):
                    out[i] = r
                    break
            else:
                out[i] = math.log(sums[1])
    return out


#: :func:`_logsumexp_rows_loop`, compiled on first use
LOGSUMEXP_ROWS = kernel(_logsumexp_rows_loop)


def logsumexp_last(a: np.ndarray, *, keepdims: bool = False) -> np.ndarray:
    """``scipy.special.logsumexp(a, axis=-1, keepdims=keepdims)`` of a real float64 array, in
    one compiled pass where it can be (the same numbers), else scipy's."""
    from scipy.special import logsumexp

    if a.dtype != np.float64 or a.ndim == 0 or a.shape[-1] == 0 or not LOGSUMEXP_ROWS.ready():
        return np.asarray(logsumexp(a, axis=-1, keepdims=keepdims))
    flat = np.ascontiguousarray(a).reshape(-1, a.shape[-1])
    out = LOGSUMEXP_ROWS(flat).reshape(a.shape[:-1] + ((1,) if keepdims else ()))
    return np.asarray(out)


# ---------------------------------------------------------------------- the sampler's moves
#
# One random-walk Metropolis step of :class:`~lfdfuse.estimate.smc.TemperedSMC` over every chain
# at once: in numpy a dozen passes over ``(C, M, n)`` arrays (the sampler's time besides the
# likelihood), here two loops around numpy's Cholesky factor. Every sum is taken in the order
# numpy takes it on x86-64 (its reductions and the two-lane loop of its ``einsum``), so the
# compiled step gives the bits of :func:`move_frame_reference` and :func:`move_propose_reference`
# there; the tests hold the two to 1e-12 everywhere.


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


def _short_sum(x: np.ndarray, n: int) -> float:
    """numpy's pairwise sum of ``x[:n]`` for ``n ≤ 128`` (one leaf: eight running sums)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += x[i]
        return res
    r0 = x[0]
    r1 = x[1]
    r2 = x[2]
    r3 = x[3]
    r4 = x[4]
    r5 = x[5]
    r6 = x[6]
    r7 = x[7]
    i = 8
    stop = n - n % 8
    while i < stop:
        r0 += x[i]
        r1 += x[i + 1]
        r2 += x[i + 2]
        r3 += x[i + 3]
        r4 += x[i + 4]
        r5 += x[i + 5]
        r6 += x[i + 6]
        r7 += x[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += x[i]
        i += 1
    return res


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
    for c in range(c_count):
        r = ref[c]
        for p in range(m):
            for i in range(n):
                row[i] = logw[c, p, i] if mask[c, i] else 0.0
            prior[c, p] = alpha * _short_sum(row, n)
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
            prior_new[c, p] = alpha * _short_sum(row, n)
    return logw_new, prior, prior_new


#: :func:`_move_propose_loop`, compiled on first use
MOVE_PROPOSE = kernel(_move_propose_loop, calls=[_short_sum, _logsumexp_rows_loop])


# ---------------------------------------------------------------------- adaptive tempering


def next_delta_reference(ll: np.ndarray, room: np.ndarray, target: float) -> np.ndarray:
    """Per chain the temperature increment ``(C,)`` that brings the effective sample size of the
    incremental weights ``L^δ`` to ``target``, ``δ`` at most ``room (C,)``: all of it when that
    keeps the ESS at the target, else 30 bisections (and never below ``min(room, 1e-6)``: a
    chain whose every step collapses still advances). ``ll (C, M)``: the particles' log-likelihoods."""
    from lfdfuse.estimate.resampling import ess

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
    stack_lo = np.empty(64, dtype=np.int64)
    stack_n = np.empty(64, dtype=np.int64)
    stack_st = np.empty(64, dtype=np.int64)
    vals = np.empty(64)
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
            vp = 0
            stack_lo[0] = 0
            stack_n[0] = m
            stack_st[0] = 0
            sp = 1
            while sp > 0:
                base = stack_lo[sp - 1]
                cnt = stack_n[sp - 1]
                if cnt <= 128:
                    sp -= 1
                    if cnt < 8:
                        res = 0.0
                        for k in range(cnt):
                            res += w[base + k]
                    else:
                        a0 = w[base]
                        a1 = w[base + 1]
                        a2 = w[base + 2]
                        a3 = w[base + 3]
                        a4 = w[base + 4]
                        a5 = w[base + 5]
                        a6 = w[base + 6]
                        a7 = w[base + 7]
                        k = 8
                        stop = cnt - cnt % 8
                        while k < stop:
                            a0 += w[base + k]
                            a1 += w[base + k + 1]
                            a2 += w[base + k + 2]
                            a3 += w[base + k + 3]
                            a4 += w[base + k + 4]
                            a5 += w[base + k + 5]
                            a6 += w[base + k + 6]
                            a7 += w[base + k + 7]
                            k += 8
                        res = ((a0 + a1) + (a2 + a3)) + ((a4 + a5) + (a6 + a7))
                        while k < cnt:
                            res += w[base + k]
                            k += 1
                    vals[vp] = res
                    vp += 1
                elif stack_st[sp - 1] == 0:
                    stack_st[sp - 1] = 1
                    half = cnt // 2
                    half -= half % 8
                    stack_lo[sp] = base + half
                    stack_n[sp] = cnt - half
                    stack_st[sp] = 0
                    stack_lo[sp + 1] = base
                    stack_n[sp + 1] = half
                    stack_st[sp + 1] = 0
                    sp += 2
                else:
                    sp -= 1
                    vals[vp - 2] = vals[vp - 2] + vals[vp - 1]
                    vp -= 1
            total = vals[0]
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
NEXT_DELTA = kernel(_next_delta_loop)
