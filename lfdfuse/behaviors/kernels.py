"""Compiled loops of the per-scan sensing: the opening sensors and the laser primitives.

A live run senses one scan per tick, and there numpy's per-call cost, not the arithmetic, is
the time: a few dozen array operations on 181 beams each. These loops do a scan's work in one
call. Each stands for a numpy function that stays the reference
(:func:`~lfdfuse.behaviors.openings.side_openings_reference`,
:func:`~lfdfuse.behaviors.openings.ahead_range_reference`, the primitives of
:mod:`lfdfuse.behaviors.library`) and gives the same bits: comparisons and counts are exact,
the beam bearings come in wrapped by numpy (no transcendental function of numba's own enters a
result), and a sum over beams is numpy's own pairwise sum (:func:`lfdfuse.kernels.pairwise.pairwise_sum`,
operation for operation), so a scan computed alone, live, equals the same scan computed in a log.

Every loop is a :func:`lfdfuse.kernels.jit.kernel`: nothing here imports numba.
"""

from __future__ import annotations

import math

import numpy as np

from lfdfuse.kernels.jit import kernel
from lfdfuse.kernels.pairwise import STACK, pairwise_sum


def _side_open_loop(
    r: np.ndarray,
    a: np.ndarray,
    far_m: float,
    inner: float,
    outer: float,
    fraction: float,
    out: np.ndarray,
) -> None:
    """``out (N, 2)``: an opening on the left / right of each scan ``r (N, B)``, bearings ``a``
    ``(N, B)`` or ``(1, B)`` (wrapped); as :func:`~lfdfuse.behaviors.openings.side_openings_reference`."""
    n, b = r.shape
    shared = a.shape[0] == 1
    for i in range(n):
        ai = 0 if shared else i
        for side in range(2):
            sign = 1.0 if side == 0 else -1.0
            count = 0
            far = 0
            for j in range(b):
                x = sign * a[ai, j]
                if x >= inner and x <= outer:
                    count += 1
                    v = r[i, j]
                    if not np.isfinite(v) or v <= 0.0 or v >= far_m:
                        far += 1
            out[i, side] = count > 0 and far / count >= fraction


def _ahead_loop(r: np.ndarray, a: np.ndarray, beam: float) -> float:
    """The median range of the beams within ``beam`` of straight ahead (bearings ``a`` wrapped),
    a beam with no return far; inf when no beam looks there. As
    :func:`~lfdfuse.behaviors.openings.ahead_range_reference`."""
    vals = np.empty(r.shape[0])
    k = 0
    for j in range(r.shape[0]):
        if abs(a[j]) <= beam:
            v = r[j]
            vals[k] = v if np.isfinite(v) and v > 0.0 else np.inf
            k += 1
    if k == 0:
        return np.inf
    s = np.sort(vals[:k])
    h = k // 2
    return float(s[h]) if k % 2 else float((s[h - 1] + s[h]) / 2.0)


def _corridor_loop(r: np.ndarray, left: np.ndarray, right: np.ndarray, open_m: float) -> bool:
    """Walls abeam on both sides (beam indices ``left``, ``right``), their medians at most
    ``open_m`` apart; as :meth:`~lfdfuse.behaviors.openings.OpeningSensor._in_corridor`."""
    if left.shape[0] == 0 or right.shape[0] == 0:
        return False
    total = 0.0
    for side in range(2):
        idx = left if side == 0 else right
        k = idx.shape[0]
        vals = np.empty(k)
        for m in range(k):
            v = r[idx[m]]
            vals[m] = v if np.isfinite(v) and v > 0.0 else np.inf
        s = np.sort(vals)
        h = k // 2
        total += s[h] if k % 2 else (s[h - 1] + s[h]) / 2.0
    return total <= open_m


def _held_loop(
    r: np.ndarray,
    side: np.ndarray,
    ahead: np.ndarray,
    far_m: float,
    inner: float,
    outer: float,
    fraction: float,
    beam: float,
) -> tuple[bool, bool, float]:
    """One scan ``r (B,)`` as :meth:`~lfdfuse.behaviors.openings.OpeningSensor.update` senses it
    at the held heading, in one call: the open flags (left, right) of :func:`_side_open_loop` over
    the bearings ``side`` and the way ahead of :func:`_ahead_loop` over the bearings ``ahead``."""
    r2 = np.empty((1, r.shape[0]))
    a2 = np.empty((1, side.shape[0]))
    for j in range(r.shape[0]):
        r2[0, j] = r[j]
    for j in range(side.shape[0]):
        a2[0, j] = side[j]
    out = np.zeros((1, 2), dtype=np.bool_)
    _side_open_loop(r2, a2, far_m, inner, outer, fraction, out)
    return out[0, 0], out[0, 1], _ahead_loop(r, ahead, beam)


SIDE_OPEN = kernel(_side_open_loop)
AHEAD = kernel(_ahead_loop)
CORRIDOR = kernel(_corridor_loop)
HELD = kernel(_held_loop, calls=[_side_open_loop, _ahead_loop])


#: the kinds of fused primitive a :func:`_pool_loop` op computes (``ops[m, 0]``)
AVOID, WANDER, WALL_ATTRACT, WALL_SIDE, SONAR_AVOID = 0, 1, 2, 3, 4


def _pool_loop(
    r: np.ndarray,
    own: np.ndarray,
    max_range: float,
    d: float,
    sonar: np.ndarray,
    sonar_lim: float,
    thr: float,
    ops: np.ndarray,
    sectors: np.ndarray,
    dirs: np.ndarray,
    vec: np.ndarray,
    app: np.ndarray,
) -> None:
    """The fused laser and sonar primitives of :func:`~lfdfuse.behaviors.primitives.compute`
    over scans ``r (N, B)`` (and ``sonar (N, S)``): op ``m`` is ``(kind, sector, column)`` with
    the directions ``dirs[m]`` it pools (``(B, 2)``; for the sonar the first ``S`` rows). Writes
    ``vec[:, column]`` (zero where not applicable) and ``app[:, column]``, as the numpy
    primitives (``Scan.near``, ``dot``, ``pool_strongest``) compute them, bit for bit."""
    n, b = r.shape
    n_s = sonar.shape[1]
    size = max(b, n_s)
    near = np.zeros(size, dtype=np.bool_)
    rn = np.empty(size)
    push = np.empty(size)
    w = np.empty(size)
    buf = np.empty(size)
    stack_lo = np.empty(STACK, dtype=np.int64)
    stack_n = np.empty(STACK, dtype=np.int64)
    stack_st = np.empty(STACK, dtype=np.int64)
    vals = np.empty(STACK)
    s = np.empty(2)
    for i in range(n):
        for j in range(b):
            x = r[i, j]
            nr = np.isfinite(x) and x > 0.0 and x < max_range and own[j] and x < d
            near[j] = nr
            rn[j] = x if nr else d
            push[j] = (d - rn[j]) / d if nr else 0.0
        for m in range(ops.shape[0]):
            kind = ops[m, 0]
            sec = ops[m, 1]
            col = ops[m, 2]
            length = b
            any_ = False
            mag = 0.0
            rmin = np.inf
            if kind == AVOID:
                for j in range(b):
                    w[j] = push[j]
                    any_ = any_ or near[j]
                    mag = max(mag, push[j])
            elif kind == WANDER:
                cnt = 0
                for j in range(b):
                    o = (not near[j]) and sectors[sec, j]
                    cnt += sectors[sec, j]
                    w[j] = 1.0 if o else 0.0
                    any_ = any_ or o
            elif kind == WALL_ATTRACT or kind == WALL_SIDE:
                for j in range(b):
                    h = near[j] and sectors[sec, j]
                    any_ = any_ or h
                    if kind == WALL_ATTRACT:
                        w[j] = 1.0 if h else 0.0
                        if h:
                            rmin = min(rmin, rn[j])
                    else:
                        w[j] = push[j] if h else 0.0
                        mag = max(mag, w[j])
            else:  # SONAR_AVOID
                length = n_s
                for j in range(n_s):
                    x = sonar[i, j]
                    ok = np.isfinite(x) and x > 0.0 and x < sonar_lim
                    w[j] = (thr - x) / thr if ok else 0.0
                    any_ = any_ or ok
                    mag = max(mag, w[j])
            app[i, col] = any_
            if not any_:
                vec[i, col, 0] = 0.0
                vec[i, col, 1] = 0.0
                continue
            for c in range(2):
                for j in range(length):
                    buf[j] = w[j] * dirs[m, j, c]
                s[c] = pairwise_sum(buf, length, stack_lo, stack_n, stack_st, vals)
            if kind == WANDER:
                vec[i, col, 0] = s[0] / max(cnt, 1)
                vec[i, col, 1] = s[1] / max(cnt, 1)
                continue
            norm = math.hypot(s[0], s[1])
            if kind == WALL_ATTRACT:
                mag = rmin / d if np.isfinite(rmin) else 0.0
            scale = mag / norm if norm > 1e-12 else 0.0
            vec[i, col, 0] = s[0] * scale
            vec[i, col, 1] = s[1] * scale


POOL = kernel(_pool_loop, calls=[pairwise_sum])
