"""Segments: distances, ray intersections, and the (segment, cell) pairs of a grid within reach.

The float64 solves the raycaster (:mod:`lfdfuse.world.raycast`) and the planner build on; the
compiled loops (:mod:`lfdfuse.world.raycast_kernel`) repeat them operation for operation.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from lfdfuse.kernels.jit import Warmup
from lfdfuse.world import raycast_kernel as _k

_EPS = 1e-12
#: most (segment, cell) pairs examined at once while building the index
_BUILD_CHUNK = 1_000_000
#: calls (casts, clearances, lines of sight) a process answers with the numpy reference before it
#: loads the compiled loops: loading numba and its cached kernels costs about a second of CPU,
#: more than a short run's calls take in numpy (the answers are the same either way)
WARMUP = Warmup(1000)
#: (segment, cell) pairs for which :func:`near_pairs` loads the compiled loop before that
_COMPILED_PAIRS = 4_000_000


def _point_segment_distance(px: np.ndarray, py: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Distances ``(P, S)`` from points ``(P,)`` to segments ``(S, 4)``."""
    ax, ay, bx, by = (seg[:, i][None, :] for i in range(4))
    ex, ey = bx - ax, by - ay
    ll = ex * ex + ey * ey
    t = ((px[:, None] - ax) * ex + (py[:, None] - ay) * ey) / np.where(ll > 0, ll, 1.0)
    t = np.clip(t, 0.0, 1.0)
    dx = ax + t * ex - px[:, None]
    dy = ay + t * ey - py[:, None]
    return np.asarray(np.sqrt(dx * dx + dy * dy))


def _pair_distance(px: np.ndarray, py: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Distances ``(N,)`` from points ``(N,)`` to segments ``(N, 4)``, pair by pair.

    The same operations as :func:`_point_segment_distance`, so the same values.
    """
    ax, ay, bx, by = seg[:, 0], seg[:, 1], seg[:, 2], seg[:, 3]
    ex, ey = bx - ax, by - ay
    ll = ex * ex + ey * ey
    t = np.clip(((px - ax) * ex + (py - ay) * ey) / np.where(ll > 0, ll, 1.0), 0.0, 1.0)
    dx = ax + t * ex - px
    dy = ay + t * ey - py
    return np.asarray(np.sqrt(dx * dx + dy * dy))


def near_pairs(
    segments: np.ndarray, *, x0: float, y0: float, cell_m: float, nx: int, ny: int, reach_m: float
) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Every (segment, cell) pair of a grid whose cell centre is within ``reach_m`` of the segment.

    The grid has ``nx × ny`` cells of ``cell_m`` from ``(x0, y0)``; cell ``(i, j)`` has its centre
    at ``(x0 + (i + ½)·cell_m, y0 + (j + ½)·cell_m)``. Yields chunks ``(segment ids, i, j,
    distance m)``, each ``(N,)``. Work grows with segments × (reach / cell)², not with cells ×
    segments.
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    n_seg = len(seg)
    i0 = np.ceil((np.minimum(seg[:, 0], seg[:, 2]) - reach_m - x0) / cell_m - 0.5)
    i1 = np.floor((np.maximum(seg[:, 0], seg[:, 2]) + reach_m - x0) / cell_m - 0.5)
    j0 = np.ceil((np.minimum(seg[:, 1], seg[:, 3]) - reach_m - y0) / cell_m - 0.5)
    j1 = np.floor((np.maximum(seg[:, 1], seg[:, 3]) + reach_m - y0) / cell_m - 0.5)
    i0, i1 = np.clip(i0, 0, nx).astype(np.int64), np.clip(i1, -1, nx - 1).astype(np.int64)
    j0, j1 = np.clip(j0, 0, ny).astype(np.int64), np.clip(j1, -1, ny - 1).astype(np.int64)
    nj = np.maximum(j1 - j0 + 1, 0)
    count = np.maximum(i1 - i0 + 1, 0) * nj
    ends = np.cumsum(count)
    start = 0
    # compiled once the process casts with the compiled loops, or when the pairs are so many
    # that loading them pays at once
    compiled = (WARMUP.done or bool(n_seg) and int(ends[-1]) > _COMPILED_PAIRS) and (
        _k.near_pairs_loop.ready()
    )
    ni = np.maximum(i1 - i0 + 1, 0)
    while start < n_seg:
        done_before = int(ends[start - 1]) if start else 0
        stop = max(start + 1, int(np.searchsorted(ends, done_before + _BUILD_CHUNK, "right")))
        if compiled:
            size = int(ends[stop - 1]) - done_before
            s, ci, cj = (np.empty(size, np.int64) for _ in range(3))
            d = np.empty(size)
            args = (x0, y0, cell_m, reach_m, s, ci, cj, d)
            n = _k.near_pairs_loop(seg, start, stop, i0, j0, ni, nj, *args)
            yield s[:n], ci[:n], cj[:n], d[:n]
            start = stop
            continue
        cnt = count[start:stop]
        s = np.repeat(np.arange(start, stop), cnt)
        local = np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        ci = i0[s] + local // nj[s]
        cj = j0[s] + local % nj[s]
        d = _pair_distance(x0 + (ci + 0.5) * cell_m, y0 + (cj + 0.5) * cell_m, seg[s])
        keep = d <= reach_m
        yield s[keep], ci[keep], cj[keep], d[keep]
        start = stop


def intersect(ox: np.ndarray, oy: np.ndarray, dx: np.ndarray, dy: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Ray parameters ``(R, S)`` at which rays hit segments; ``inf`` where they miss.

    Rays are ``o + t·d`` with unit ``d``, so ``t`` is a distance in metres. Arrays ``ox, oy,
    dx, dy`` have shape ``(R,)``; ``seg`` has shape ``(S, 4)``.
    """
    ax, ay = seg[:, 0][None, :], seg[:, 1][None, :]
    ex, ey = (seg[:, 2] - seg[:, 0])[None, :], (seg[:, 3] - seg[:, 1])[None, :]
    dxc, dyc = dx[:, None], dy[:, None]
    denom = dxc * ey - dyc * ex
    wx, wy = ax - ox[:, None], ay - oy[:, None]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # 1/subnormal: inf
        inv = 1.0 / denom
        t = (wx * ey - wy * ex) * inv
        u = (wx * dyc - wy * dxc) * inv
    parallel = np.abs(denom) <= _EPS
    hit = ~parallel & (t >= 0.0) & (u >= -1e-12) & (u <= 1.0 + 1e-12)
    out = np.where(hit, t, np.inf)
    if parallel.any():
        out = np.where(parallel, _collinear(wx, wy, ex, ey, dxc, dyc, out), out)
    return out


def _collinear(
    wx: np.ndarray,
    wy: np.ndarray,
    ex: np.ndarray,
    ey: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
    out: np.ndarray,
) -> np.ndarray:
    """For parallel ray/segment pairs: a beam along a wall hits the nearest point ahead of it."""
    collinear = np.abs(wx * dy - wy * dx) <= 1e-9
    ta = wx * dx + wy * dy
    tb = (wx + ex) * dx + (wy + ey) * dy
    inside = (ta <= 0.0) & (tb >= 0.0) | (tb <= 0.0) & (ta >= 0.0)
    ahead = np.where(np.minimum(ta, tb) >= 0.0, np.minimum(ta, tb), np.inf)
    return np.where(collinear, np.where(inside, 0.0, ahead), out)
