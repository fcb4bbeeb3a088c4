"""The compiled loops of the ``pf`` sampler's likelihood (:mod:`lfdfuse.estimate.model`).

Each is a plain loop that numba compiles on first use (:mod:`lfdfuse.kernels.jit`); the numpy function
it stands for stays the reference (:func:`sum_cos_reference`,
:func:`~lfdfuse.estimate.model.log_marginal`), and the tests hold the two to 1e-12. A long row's
particles are shared out over the machine's cores (:func:`continuous_loglik`: threads, the loops
release the GIL), each particle computed alone, so the split changes no bit. The sampler's other
steps: :mod:`lfdfuse.estimate.smc_kernels`; the discrete command model's likelihood:
:mod:`lfdfuse.estimate.discrete_kernels`.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from typing import Protocol

import numpy as np

from lfdfuse.kernels.jit import kernel
from lfdfuse.kernels.pairwise import STACK, pairwise_sum


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
    data: RowSteps, w: np.ndarray, of: int, kappas: np.ndarray, log_norm: np.ndarray
) -> np.ndarray:
    """``log p(data | w)`` of a continuous row for weights ``w (P, n)``, a subset of ``of``
    particles (:data:`SUM_COS` then :data:`LOG_MARGINAL`, both ready), the particles shared out
    over the machine's cores when the row is long enough to pay for it. Each particle's numbers
    are computed on their own, in the same order, whichever thread and share it falls in: the
    result does not depend on the split."""
    wt = np.ascontiguousarray(w.T, dtype=np.float64)
    block = max(16, BLOCK_ELEMENTS // max(1, of))
    along, across, steps = data.along, data.across, float(data.steps)
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
#: ``math.exp(x) < 2^-53`` for every ``x`` below this (``exp(-37) ≈ 8.5e-17``)
_EXP_NEGLIGIBLE = -37.0


def _log_marginal_loop(s: np.ndarray, steps: float, kappas: np.ndarray, log_norm: np.ndarray) -> np.ndarray:
    """:func:`~lfdfuse.estimate.model.log_marginal` for ``S (P,)`` of rows of ``steps`` steps, as one loop."""
    j_count = len(kappas)
    out = np.empty(len(s))
    terms = np.empty(j_count)
    log_j = math.log(j_count)
    scaled = np.empty(j_count)
    for j in range(j_count):
        scaled[j] = steps * log_norm[j]
    for p in range(len(s)):
        top = -np.inf
        gap = s[p] - steps
        for j in range(j_count):
            x = kappas[j] * gap - scaled[j]
            terms[j] = x
            if x > top:
                top = x
        acc = 0.0
        for j in range(j_count):
            d = terms[j] - top
            # exp of anything below -745.2 is +0.0, and adding +0.0 leaves the sum as it is: the
            # nodes far from the peak (most of them, on a long row) cost no exp (NaN still adds)
            if d < _EXP_ZERO:
                continue
            # once the sum holds the peak's 1.0, a term below 2^-53 (half its last place) rounds
            # away: adding it leaves the sum's bits as they are, so its exp is not computed
            if acc >= 1.0 and d < _EXP_NEGLIGIBLE:
                continue
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
    stack_lo = np.empty(STACK, dtype=np.int64)
    stack_n = np.empty(STACK, dtype=np.int64)
    stack_st = np.empty(STACK, dtype=np.int64)
    vals = np.empty(STACK)
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
            sums[pass_] = pairwise_sum(buf, length, stack_lo, stack_n, stack_st, vals)
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
LOGSUMEXP_ROWS = kernel(_logsumexp_rows_loop, calls=[pairwise_sum])


def logsumexp_last(a: np.ndarray, *, keepdims: bool = False) -> np.ndarray:
    """``scipy.special.logsumexp(a, axis=-1, keepdims=keepdims)`` of a real float64 array, in
    one compiled pass where it can be (the same numbers), else scipy's."""
    from scipy.special import logsumexp

    if a.dtype != np.float64 or a.ndim == 0 or a.shape[-1] == 0 or not LOGSUMEXP_ROWS.ready():
        return np.asarray(logsumexp(a, axis=-1, keepdims=keepdims))
    flat = np.ascontiguousarray(a).reshape(-1, a.shape[-1])
    out = LOGSUMEXP_ROWS(flat).reshape(a.shape[:-1] + ((1,) if keepdims else ()))
    return np.asarray(out)
