"""Compiled loops of the raycaster: a scan, a clearance and a line of sight over one cell's candidates.

:class:`~lfdfuse.world.raycast.RayCaster` keeps, per grid cell, the segments that can be hit
from inside it, sorted by a lower bound of their distance from anywhere in the cell. These
loops walk that list nearest first and stop as soon as the answer is no farther than the next
segment's bound: a beam that hits a wall 1 m away looks at the walls within about 1 m only.

Each (beam, segment) pair is solved by one helper, :func:`_solve` (compiled with each loop that
calls it), with the same float64 operations, in the same order, as
:func:`~lfdfuse.world.segments.intersect` (the parallel and collinear cases included), and a
minimum does not depend on the order it is taken in, so the results equal the numpy
reference's (a range of zero is +0.0 in both). The beam directions come in precomputed (numpy's ``cos``/``sin``), so no
transcendental function of numba's own enters a result.

Every loop is a :func:`lfdfuse.kernels.jit.kernel`: nothing here imports numba.
"""

from __future__ import annotations

import math

import numpy as np

from lfdfuse.kernels.jit import kernel


def _solve(wx: float, wy: float, ex: float, ey: float, ux: float, uy: float) -> float:
    """The range along the unit ray ``(ux, uy)`` to the segment from ``(wx, wy)`` (relative to
    the ray's origin) along ``(ex, ey)``, or −1.0 when the ray misses it: the solve of
    :func:`~lfdfuse.world.segments.intersect`, operation for operation."""
    denom = ux * ey - uy * ex
    if abs(denom) <= 1e-12:
        # parallel: a beam along a wall hits the nearest point ahead of it
        if abs(wx * uy - wy * ux) > 1e-9:
            return -1.0
        ta = wx * ux + wy * uy
        tb = (wx + ex) * ux + (wy + ey) * uy
        if (ta <= 0.0 and tb >= 0.0) or (tb <= 0.0 and ta >= 0.0):
            return 0.0
        t = min(ta, tb)
        return t if t >= 0.0 else -1.0
    inv = 1.0 / denom
    t = (wx * ey - wy * ex) * inv
    u = (wx * uy - wy * ux) * inv
    if not (t >= 0.0 and u >= -1e-12 and u <= 1.0 + 1e-12):
        return -1.0
    return t


def _cast_loop(
    seg: np.ndarray,
    ids: np.ndarray,
    lower: np.ndarray,
    x: float,
    y: float,
    dx: np.ndarray,
    dy: np.ndarray,
    max_range: float,
    out: np.ndarray,
) -> None:
    """``out[b]``: range along beam ``(dx[b], dy[b])`` from ``(x, y)`` over candidates ``ids``
    (sorted by their lower-bound distance ``lower``), at most ``max_range``."""
    n = ids.shape[0]
    for b in range(dx.shape[0]):
        ux = dx[b]
        uy = dy[b]
        best = max_range
        for k in range(n):
            if lower[k] >= best:
                break
            s = ids[k]
            ax = seg[s, 0]
            ay = seg[s, 1]
            wx = ax - x
            wy = ay - y
            ex = seg[s, 2] - ax
            ey = seg[s, 3] - ay
            t = _solve(wx, wy, ex, ey, ux, uy)
            if t < 0.0:
                continue
            if t < best:
                best = t
        out[b] = best + 0.0  # +0.0 for a range of zero, as the reference


def _clearance_loop(
    seg: np.ndarray, ids: np.ndarray, lower: np.ndarray, px: float, py: float, cap: float
) -> float:
    """Distance from ``(px, py)`` to the nearest candidate, at most ``cap``: the operations of
    :func:`~lfdfuse.world.segments._point_segment_distance`."""
    best = cap
    for k in range(ids.shape[0]):
        if lower[k] >= best:
            break
        s = ids[k]
        ax = seg[s, 0]
        ay = seg[s, 1]
        ex = seg[s, 2] - ax
        ey = seg[s, 3] - ay
        ll = ex * ex + ey * ey
        t = ((px - ax) * ex + (py - ay) * ey) / (ll if ll > 0 else 1.0)
        t = min(max(t, 0.0), 1.0)
        qx = ax + t * ex - px
        qy = ay + t * ey - py
        d = math.sqrt(qx * qx + qy * qy)
        if d < best:
            best = d
    return best


def _blocked_loop(
    seg: np.ndarray, ids: np.ndarray, lower: np.ndarray, x: float, y: float, ux: float, uy: float, dist: float
) -> bool:
    """True when the unit ray from ``(x, y)`` along ``(ux, uy)`` hits a candidate before ``dist``."""
    for k in range(ids.shape[0]):
        if lower[k] >= dist:
            break
        s = ids[k]
        ax = seg[s, 0]
        ay = seg[s, 1]
        wx = ax - x
        wy = ay - y
        ex = seg[s, 2] - ax
        ey = seg[s, 3] - ay
        t = _solve(wx, wy, ex, ey, ux, uy)
        if t < 0.0:
            continue
        if t < dist:
            return True
    return False


cast_loop = kernel(_cast_loop, calls=[_solve])
clearance_loop = kernel(_clearance_loop)
blocked_loop = kernel(_blocked_loop, calls=[_solve])


def _sector_lists(bins: np.ndarray, sectors: int, starts: np.ndarray) -> np.ndarray:
    """Per angular sector, the candidates whose sectors ``bins[k]`` (first, last; last may pass
    ``sectors`` and wraps round) cover it, in candidate order: fills ``starts`` ``(sectors + 1,)``
    and returns the candidate positions, grouped by sector."""
    counts = np.zeros(sectors, np.int64)
    for k in range(bins.shape[0]):
        for s in range(bins[k, 0], bins[k, 1] + 1):
            counts[s % sectors] += 1
    starts[0] = 0
    for s in range(sectors):
        starts[s + 1] = starts[s] + counts[s]
    entries = np.empty(starts[sectors], np.int32)
    fill = starts[:sectors].copy()
    for k in range(bins.shape[0]):
        for s in range(bins[k, 0], bins[k, 1] + 1):
            r = s % sectors
            entries[fill[r]] = k
            fill[r] += 1
    return entries


def _cast_sectors_loop(
    cand: np.ndarray,
    starts: np.ndarray,
    entries: np.ndarray,
    x: float,
    y: float,
    angles: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
    max_range: float,
    out: np.ndarray,
) -> None:
    """:func:`_cast_loop` over only the candidates listed for each beam's angular sector.

    ``cand`` ``(K, 5)``: the cell's candidates nearest first, as ``[ax, ay, bx − ax, by − ay,
    lower bound]``; ``entries[starts[s]:starts[s + 1]]`` the positions in ``cand`` of those a
    ray in sector ``s`` (of ``len(starts) − 1`` round the circle) can hit, in the same order.
    """
    sectors = starts.shape[0] - 1
    two_pi = 2.0 * math.pi
    for b in range(dx.shape[0]):
        ux = dx[b]
        uy = dy[b]
        best = max_range
        phi = angles[b] % two_pi
        if phi >= two_pi:
            phi = 0.0
        sec = min(int(phi * (sectors / two_pi)), sectors - 1)
        for e in range(starts[sec], starts[sec + 1]):
            k = entries[e]
            if cand[k, 4] >= best:
                break
            wx = cand[k, 0] - x
            wy = cand[k, 1] - y
            ex = cand[k, 2]
            ey = cand[k, 3]
            t = _solve(wx, wy, ex, ey, ux, uy)
            if t < 0.0:
                continue
            if t < best:
                best = t
        out[b] = best + 0.0  # +0.0 for a range of zero, as the reference


sector_lists = kernel(_sector_lists)
cast_sectors_loop = kernel(_cast_sectors_loop, calls=[_solve])


def _near_pairs_loop(
    seg: np.ndarray,
    start: int,
    stop: int,
    i0: np.ndarray,
    j0: np.ndarray,
    ni: np.ndarray,
    nj: np.ndarray,
    x0: float,
    y0: float,
    cell_m: float,
    reach_m: float,
    out_s: np.ndarray,
    out_i: np.ndarray,
    out_j: np.ndarray,
    out_d: np.ndarray,
) -> int:
    """The pairs of segments ``start:stop`` and the cells of their ``ni × nj`` boxes from
    ``(i0, j0)`` whose centre is within ``reach_m``, in the order and with the distances of
    :func:`~lfdfuse.world.segments.near_pairs` (its ``_pair_distance``, operation for operation);
    returns how many were written."""
    n = 0
    for s in range(start, stop):
        ax = seg[s, 0]
        ay = seg[s, 1]
        ex = seg[s, 2] - ax
        ey = seg[s, 3] - ay
        ll = ex * ex + ey * ey
        div = ll if ll > 0 else 1.0
        for a in range(ni[s]):
            ci = i0[s] + a
            px = x0 + (ci + 0.5) * cell_m
            for b in range(nj[s]):
                cj = j0[s] + b
                py = y0 + (cj + 0.5) * cell_m
                t = ((px - ax) * ex + (py - ay) * ey) / div
                t = min(max(t, 0.0), 1.0)
                qx = ax + t * ex - px
                qy = ay + t * ey - py
                d = math.sqrt(qx * qx + qy * qy)
                if d <= reach_m:
                    out_s[n] = s
                    out_i[n] = ci
                    out_j[n] = cj
                    out_d[n] = d
                    n += 1
    return n


near_pairs_loop = kernel(_near_pairs_loop)
