"""The discrete command model's likelihood (:func:`~lfdfuse.estimate.model.discrete_log_marginal`):
its numpy reference and its compiled loop.

Per decision and particle: the fused heading ``φ = atan2(vy·w, vx·w)``, the observed interval
shifted by it (wrapping past ±π), the tabulated von Mises CDFs at the ``J`` κ nodes by linear
interpolation (a zero vector: the interval's width over 2π), clipped, the lapse mixed in, the log;
summed over the decisions, then the log-sum-exp over the nodes. The loop
(:data:`DISCRETE_BLOCK`) takes the fused components from the same BLAS products as the reference
and then the reference's operations in its order, with libm's functions: it gives the
reference's bits wherever numpy's log, arctan2 and hypot are libm's (x86-64 without AVX-512, for
one), and agrees to rounding elsewhere. A large block's particles are shared out over the cores
(:mod:`lfdfuse.estimate.kernels`' threads), each particle computed alone: the split changes no bit.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from typing import Protocol

import numpy as np

from lfdfuse.estimate import kernels
from lfdfuse.estimate.kernels import BLOCK_ELEMENTS, logsumexp_last
from lfdfuse.kernels.jit import kernel

#: grid cells of the tabulated von Mises CDF over a full turn (0.18°: fine for σ ≥ 2°)
CDF_GRID = 2048

_TWO_PI = 2.0 * math.pi


class DecisionSteps(Protocol):
    """What the likelihood reads of a discrete row (:class:`~lfdfuse.estimate.model.DiscreteRowData`)."""

    @property
    def vx(self) -> np.ndarray: ...

    @property
    def vy(self) -> np.ndarray: ...

    @property
    def lo(self) -> np.ndarray: ...

    @property
    def hi(self) -> np.ndarray: ...

    @property
    def commands(self) -> int | np.ndarray: ...

    @property
    def steps(self) -> int: ...


class DiscreteModel(Protocol):
    """What it reads of the model (:class:`~lfdfuse.estimate.model.FusionModel`)."""

    @property
    def lapse(self) -> float: ...

    @property
    def vm_cdf_rows(self) -> np.ndarray: ...


def cdf_at(x: np.ndarray, table: np.ndarray) -> np.ndarray:
    """The tabulated CDFs ``table (G + 1, J)`` at ``x (…)`` in ``[−π, π]`` → ``(…, J)`` (linear;
    the nodes last, so each lookup gathers one contiguous row)."""
    pos = (np.clip(x, -math.pi, math.pi) + math.pi) * (CDF_GRID / (2.0 * math.pi))
    i = np.minimum(pos.astype(np.int64), CDF_GRID - 1)
    f = (pos - i)[..., None]
    lo = table[i]
    return np.asarray(lo + f * (table[i + 1] - lo))


def discrete_log_marginal_reference(data: DecisionSteps, w: np.ndarray, model: DiscreteModel) -> np.ndarray:
    """:func:`~lfdfuse.estimate.model.discrete_log_marginal` in numpy (two BLAS products and the nodes' arrays per block
    of steps): the reference."""
    wt = np.ascontiguousarray(w.T)
    table = model.vm_cdf_rows
    j = table.shape[1]
    ll = np.zeros((w.shape[0], j))
    block = max(16, BLOCK_ELEMENTS // max(1, w.shape[0] * j))
    lapse: float | np.ndarray
    if isinstance(data.commands, np.ndarray):  # pooled demos' command sets of several sizes
        lapse = model.lapse / np.maximum(1.0, data.commands)
    else:
        lapse = model.lapse / max(1, data.commands)
    for c in range(0, data.steps, block):
        a = data.vx[c : c + block] @ wt
        b = data.vy[c : c + block] @ wt
        phi = np.arctan2(b, a)
        width = (data.hi[c : c + block] - data.lo[c : c + block])[:, None]
        lo = np.remainder(data.lo[c : c + block, None] - phi + math.pi, 2.0 * math.pi) - math.pi
        hi = lo + width
        wrap = hi > math.pi
        p = cdf_at(np.where(wrap, hi - 2.0 * math.pi, hi), table) + wrap[..., None] - cdf_at(lo, table)
        zero = np.hypot(a, b) <= 1e-12
        p = np.where(zero[..., None], (width / (2.0 * math.pi))[..., None], p)
        # (steps, particles, nodes) in place: the largest temporaries of a discrete row
        np.clip(p, 0.0, 1.0, out=p)
        p *= 1.0 - model.lapse
        p += lapse[c : c + block, None, None] if isinstance(lapse, np.ndarray) else lapse
        np.log(p, out=p)
        ll += p.sum(axis=0)
    return np.asarray(logsumexp_last(ll) - math.log(j))


def _remainder_turn(x: float) -> float:
    """``np.remainder(x, 2π)`` (the float ``%``, ``fmod`` then the divisor's sign), without the
    ``fmod`` for ``x`` within a turn of ``[0, 2π)``, where it is exact: ``x`` itself, ``x − 2π``
    (exact there, Sterbenz) or ``x + 2π`` (the one rounding the ``%`` makes too)."""
    if x == 0.0:
        return 0.0  # −0.0 too: the remainder takes the divisor's sign
    if 0.0 < x < _TWO_PI:
        return x
    if _TWO_PI <= x < 2.0 * _TWO_PI:
        return x - _TWO_PI
    if -_TWO_PI <= x < 0.0:
        return x + _TWO_PI
    return x % _TWO_PI


def _discrete_block_loop(
    a: np.ndarray,
    b: np.ndarray,
    lo: np.ndarray,
    width: np.ndarray,
    lapse: np.ndarray,
    keep: float,
    table: np.ndarray,
    ll: np.ndarray,
    first: int,
) -> None:
    """One block of steps of :func:`~lfdfuse.estimate.model.discrete_log_marginal`, added into
    ``ll (P′, J)`` in place: the fused components ``a, b (B, P)`` (the reference's BLAS
    products), each step's interval start ``lo``, width ``hi − lo`` and lapse share ``λ/m``
    ``(B,)``, ``keep = 1 − λ``, the CDF table ``(G + 1, J)``; particles ``first … first + P′``.

    Operation for operation the reference's: the interval shifted by ``φ = atan2(b, a)`` with
    numpy's remainder, each CDF by linear interpolation, the zero vector's ``width / 2π``, numpy's
    clip to ``[0, 1]``, the lapse mixed in, the log; each node's logs summed over the block's steps
    in order, then added into ``ll``. Each particle is computed on its own: a share of the
    particles gives their bits."""
    steps = a.shape[0]
    p_count, j_count = ll.shape
    grid = table.shape[0] - 1
    scale = grid / _TWO_PI
    part = np.empty((p_count, j_count))
    for t in range(steps):
        lo_t = lo[t]
        w_t = width[t]
        add = lapse[t]
        # the logs every particle of this step may share: a probability of exactly 0 or 1 (the
        # nodes of high κ, far from the interval or well inside it) and a zero vector's
        log_none = math.log(0.0 * keep + add)
        log_all = math.log(1.0 * keep + add)
        flat = w_t / _TWO_PI
        if flat == flat:  # numpy's clip: NaN stays NaN
            flat = flat if flat > 0.0 else 0.0
            flat = flat if flat < 1.0 else 1.0
        log_flat = math.log(flat * keep + add)
        for q in range(p_count):
            p = first + q
            at = a[t, p]
            bt = b[t, p]
            # |(a, b)| ≥ max(|a|, |b|): the hypot is needed only where both are tiny
            zero = abs(at) <= 1e-12 and abs(bt) <= 1e-12 and math.hypot(at, bt) <= 1e-12
            phi = math.atan2(bt, at)
            low = _remainder_turn(lo_t - phi + math.pi) - math.pi
            high = low + w_t
            wrapped = 0.0
            if high > math.pi:
                wrapped = 1.0
                high = high - _TWO_PI
            x = min(max(low, -math.pi), math.pi)  # no NaN here: a finite shift, clipped as numpy clips
            pos_lo = (x + math.pi) * scale
            i_lo = min(int(pos_lo), grid - 1)
            f_lo = pos_lo - i_lo
            x = min(max(high, -math.pi), math.pi)
            pos_hi = (x + math.pi) * scale
            i_hi = min(int(pos_hi), grid - 1)
            f_hi = pos_hi - i_hi
            for j in range(j_count):
                if zero:
                    v = log_flat
                else:
                    c_lo = table[i_lo, j]
                    c_lo = c_lo + f_lo * (table[i_lo + 1, j] - c_lo)
                    c_hi = table[i_hi, j]
                    c_hi = c_hi + f_hi * (table[i_hi + 1, j] - c_hi)
                    v = c_hi + wrapped - c_lo
                    if v <= 0.0:  # clipped to 0 (−0.0 too: the same sum)
                        v = log_none
                    elif v >= 1.0:
                        v = log_all
                    else:  # NaN too: its log is NaN, as numpy's
                        v = math.log(v * keep + add)
                if t == 0:
                    part[q, j] = v
                else:
                    part[q, j] += v
    for q in range(p_count):
        for j in range(j_count):
            ll[q, j] += part[q, j]


#: :func:`_discrete_block_loop`, compiled on first use
DISCRETE_BLOCK = kernel(_discrete_block_loop, calls=[_remainder_turn])


def _discrete_share(
    a: np.ndarray, b: np.ndarray, args: tuple[object, ...], ll: np.ndarray, lo: int, hi: int
) -> None:
    """:data:`DISCRETE_BLOCK` for the particles ``lo … hi`` (a thread's share)."""
    DISCRETE_BLOCK(a, b, *args, ll[lo:hi], lo)


def discrete_loglik(
    vx: np.ndarray,
    vy: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    lapse: np.ndarray,
    keep: float,
    w: np.ndarray,
    table: np.ndarray,
) -> np.ndarray:
    """The per-node log-likelihoods ``ll (P, J)`` of a discrete row (:data:`DISCRETE_BLOCK`,
    ready) for weights ``w (P, n)``: per block of steps the fused components by BLAS, as the
    reference takes them, then the compiled loop, the particles shared out over the cores when
    the block is large enough to pay for it (each particle's bits do not depend on the split)."""
    wt = np.ascontiguousarray(w.T)
    p_count, j_count = w.shape[0], table.shape[1]
    ll = np.zeros((p_count, j_count))
    block = max(16, BLOCK_ELEMENTS // max(1, p_count * j_count))
    cores = kernels._cores()
    for c in range(0, vx.shape[0], block):
        a = vx[c : c + block] @ wt
        b = vy[c : c + block] @ wt
        width = hi[c : c + block] - lo[c : c + block]
        args = (lo[c : c + block], width, lapse[c : c + block], keep, table)
        parts = min(cores, p_count // 64, (a.shape[0] * p_count * j_count) // kernels.SPLIT_WORK)
        if parts < 2 or not DISCRETE_BLOCK.warm_for():
            DISCRETE_BLOCK(a, b, *args, ll, 0)
            continue
        if not kernels._pool:
            kernels._pool.append(ThreadPoolExecutor(max_workers=cores - 1, thread_name_prefix="lfdfuse-pf"))
        cuts = [p_count * i // parts for i in range(parts + 1)]
        futures = [
            kernels._pool[0].submit(_discrete_share, a, b, args, ll, cuts[i], cuts[i + 1])
            for i in range(1, parts)
        ]
        DISCRETE_BLOCK(a, b, *args, ll[: cuts[1]], 0)  # this thread takes a share too
        for f in futures:
            f.result()
    return ll
