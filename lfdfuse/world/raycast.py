"""Vectorised ray–segment casting over a spatial index that stays fast on thousands of walls.

The map is a set of segments ``(S, 4)`` ``[ax, ay, bx, by]``. A uniform grid of ``cell_m``
cells lists, per cell, every segment that can be hit from anywhere inside it within
``max_range_m``, sorted nearest first and cut into *bands* of growing size (32, 128, 512, …).

A scan is cast band by band. Within a band, each segment's angular interval as seen from the
origin selects the beams that can hit it (a conservative, slightly widened filter), and only
those (beam, segment) pairs are solved exactly. A beam is finished once its nearest hit is no
farther than the next band's lower-bound distance, so a scan in a dense map stops after the
first band or two: its cost follows the walls near the robot, not the size of the map.

Intersections are the same parametric line solve in float64 as :func:`intersect`, applied to a
superset of the pairs that can hit, so results equal a brute-force cast over all segments.
The index is built per segment (the cells within reach of its bounding box), so building costs
segments × reach², never cells × segments.
"""

from __future__ import annotations

import hashlib
import math
import threading
from collections import OrderedDict

import numpy as np

from lfdfuse.world import raycast_kernel as _k
from lfdfuse.world.segments import _EPS, WARMUP, _collinear, _point_segment_distance, intersect, near_pairs

__all__ = ["RayCaster", "intersect", "near_pairs"]

_TWO_PI = 2.0 * math.pi
#: sizes of the candidate bands, nearest first; the last band takes all the rest
_BANDS = (384, 3072)
#: angular sectors of the cull of later bands (segments away from every unfinished beam)
_SECTORS = 256
#: later bands smaller than this are tested whole
_CULL_MIN = 64
#: cached per-cell band arrays, cleared when it grows past this many cells
_CACHE_CELLS = 4096
#: cached per-cell sector lists of the compiled cast, cleared when they grow past this many entries
_CACHE_ENTRIES = 16_000_000
#: casters kept by :meth:`RayCaster.shared` (their index is the costly part of a run's setup)
_SHARED_KEPT = 2
#: most grid cells; a larger world gets larger cells
_MAX_CELLS = 4_000_000
#: most (segment, cell) pairs the index may examine; more segments get larger cells
_MAX_PAIRS = 12_000_000


class _Band:
    """The segments of one band of a cell, with what a cast needs precomputed.

    ``bins`` ``(K, 2)``: per segment, the first and last of ``_SECTORS`` angular sectors from
    which a ray leaving any point of the cell can hit it (last < first + _SECTORS); None when
    the band is always tested whole.
    """

    __slots__ = ("seg", "ex", "ey", "slack", "cut_m", "bins")

    def __init__(self, seg: np.ndarray, cut_m: float, bins: np.ndarray | None = None) -> None:
        self.seg = np.ascontiguousarray(seg)
        self.ex, self.ey = self.seg[:, 2] - self.seg[:, 0], self.seg[:, 3] - self.seg[:, 1]
        length = np.hypot(self.ex, self.ey)
        # Angular widening of the beam filter, divided by |cross| = h·length (h: distance from
        # the origin to the segment's line). The exact test accepts 1e-12·length past each end
        # and a collinear beam within 1e-9 m of an end: seen from the origin, under at most
        # (1e-12·length + 1e-9) / h rad. Ten times that, and every beam when h is tiny.
        self.slack = (1e-11 * length + 1e-8) * length + 1e-30
        #: lower bound (m) of the distance from anywhere in the cell to any later band's segment
        self.cut_m = cut_m
        self.bins = bins

    def subset(self, keep: np.ndarray) -> _Band:
        out = _Band.__new__(_Band)
        out.seg, out.ex, out.ey, out.slack = self.seg[keep], self.ex[keep], self.ey[keep], self.slack[keep]
        out.cut_m, out.bins = self.cut_m, None
        return out


def _sector_bins(seg: np.ndarray, cx: float, cy: float, radius_m: float) -> np.ndarray:
    """Sectors ``(K, 2)`` (first, last) of the directions from a disc to each segment.

    Seen from any point within ``radius_m`` of ``(cx, cy)``, a point of the segment lies within
    asin(radius / d) of its direction from the centre (d: the segment's distance from it); a
    segment closer than the radius can be seen in any direction.
    """
    w = seg - np.array([cx, cy, cx, cy])
    cross = w[:, 0] * (seg[:, 3] - seg[:, 1]) - w[:, 1] * (seg[:, 2] - seg[:, 0])
    ends = np.arctan2(w[:, 1::2], w[:, 0::2])
    first = np.where(cross >= 0.0, ends[:, 0], ends[:, 1])
    width = np.mod(ends[:, 0] + ends[:, 1] - 2.0 * first, _TWO_PI)
    reach = radius_m + 1e-6
    d = _point_segment_distance(np.array([cx]), np.array([cy]), seg)[0]
    widen = np.arcsin(np.minimum(reach / np.maximum(d, reach), 1.0)) + 1e-6
    width = np.where(d > reach, width + 2.0 * widen, _TWO_PI)
    step = _TWO_PI / _SECTORS
    lo = np.floor(np.mod(first - widen, _TWO_PI) / step).astype(np.int64)
    lo = np.minimum(lo, _SECTORS - 1)
    hi = np.minimum(lo + np.ceil(width / step).astype(np.int64) + 1, lo + _SECTORS - 1)
    return np.column_stack([lo, hi])


class RayCaster:
    """Casts rays against a fixed set of segments within ``max_range_m``.

    >>> import numpy as np
    >>> rc = RayCaster(np.array([[2.0, -1.0, 2.0, 1.0]]), max_range_m=8.0)
    >>> float(rc.cast(0.0, 0.0, np.array([0.0]))[0])
    2.0
    >>> float(rc.cast(0.0, 0.0, np.array([np.pi]))[0])  # no return: the max range
    8.0
    >>> RayCaster(np.zeros((0, 4))).cast(0.0, 0.0, np.array([0.0, 1.0])).tolist()  # no walls at all
    [8.0, 8.0]
    """

    def __init__(self, segments: np.ndarray, *, max_range_m: float = 8.0, cell_m: float = 1.0) -> None:
        self.segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
        self.max_range_m = float(max_range_m)
        self.cell_m = float(cell_m)
        seg = self.segments
        if len(seg):
            xs = np.concatenate([seg[:, 0], seg[:, 2]])
            ys = np.concatenate([seg[:, 1], seg[:, 3]])
            self.x0 = float(xs.min()) - self.max_range_m
            self.y0 = float(ys.min()) - self.max_range_m
            x1 = float(xs.max()) + self.max_range_m
            y1 = float(ys.max()) + self.max_range_m
        else:
            self.x0 = self.y0 = 0.0
            x1 = y1 = self.cell_m
        # any cell size gives the same results; a huge world gets coarser cells, not huge memory
        self.cell_m = max(self.cell_m, math.sqrt((x1 - self.x0) * (y1 - self.y0) / _MAX_CELLS))
        span = np.abs(seg[:, 2:] - seg[:, :2]) + 2.0 * self.max_range_m
        while True:
            reach = span + 2.0 * self.cell_m * math.sqrt(0.5)
            if float(np.prod(np.ceil(reach / self.cell_m) + 1.0, axis=1).sum()) <= _MAX_PAIRS:
                break
            self.cell_m *= 1.25
        self.nx = max(1, math.ceil((x1 - self.x0) / self.cell_m))
        self.ny = max(1, math.ceil((y1 - self.y0) / self.cell_m))
        self._build_index()
        self._all = [_Band(self.segments, math.inf)]
        self._cache: dict[int, list[_Band]] = {}
        self._sector_cache: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._sector_entries = 0

    _shared: OrderedDict[tuple[bytes, float, float], RayCaster] = OrderedDict()
    _shared_lock = threading.Lock()

    @classmethod
    def shared(cls, segments: np.ndarray, *, max_range_m: float = 8.0, cell_m: float = 1.0) -> RayCaster:
        """A caster of these segments, built once per process for the last few maps: every run
        in a world (each start of ``execute``, each test) casts on the same index. Casting has no
        state that changes a result, so a shared caster answers as a new one would."""
        seg = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
        key = (hashlib.blake2b(seg.tobytes(), digest_size=20).digest(), float(max_range_m), float(cell_m))
        with cls._shared_lock:
            rc = cls._shared.get(key)
            if rc is not None:
                cls._shared.move_to_end(key)
                return rc
        rc = cls(seg, max_range_m=max_range_m, cell_m=cell_m)
        with cls._shared_lock:
            cls._shared[key] = rc
            while len(cls._shared) > _SHARED_KEPT:
                cls._shared.popitem(last=False)
        return rc

    def _build_index(self) -> None:
        """Per cell, the segments within max range + half diagonal of its centre, nearest first.

        Sets ``_index`` (segment ids, grouped by cell), ``_offsets`` ``(cells + 1,)`` and
        ``_lower_um`` (per entry, a lower bound in whole micrometres of the distance from
        anywhere in the cell to the segment, non-decreasing within a cell).
        """
        half_diag = self.cell_m * math.sqrt(0.5)
        reach = self.max_range_m + half_diag
        keys: list[np.ndarray] = []
        ids: list[np.ndarray] = []
        # the sort key packs (cell, lower bound in whole micrometres, rounded down) into one int64
        q_max = (1 << 32) - 1
        for s, ci, cj, d in near_pairs(
            self.segments, x0=self.x0, y0=self.y0, cell_m=self.cell_m, nx=self.nx, ny=self.ny, reach_m=reach
        ):
            lower = np.maximum(d - half_diag - 1e-9, 0.0)
            q = np.minimum(np.floor(lower * 1e6), q_max).astype(np.int64)
            keys.append(((ci * self.ny + cj) << 32) | q)
            ids.append(s)
        key = np.concatenate(keys) if keys else np.zeros(0, np.int64)
        order = np.argsort(key, kind="stable")
        key = key[order]
        self._index = (np.concatenate(ids)[order] if ids else np.zeros(0, np.int64)).astype(np.int32)
        self._lower_um = (key & q_max).astype(np.uint32)
        cells = key >> 32
        self._offsets = np.searchsorted(cells, np.arange(self.nx * self.ny + 1)).astype(np.int64)
        # the bounds in metres, as the bands' cuts read them; outside the grid: every segment
        self._lower_m = self._lower_um.astype(np.float64) * 1e-6
        self._all_ids = np.arange(len(self.segments), dtype=np.int32)
        self._all_lower = np.zeros(len(self.segments))

    def _cell(self, x: float, y: float) -> int:
        """The grid cell holding ``(x, y)``, or -1 outside the grid."""
        i = int((x - self.x0) // self.cell_m)
        j = int((y - self.y0) // self.cell_m)
        return i * self.ny + j if 0 <= i < self.nx and 0 <= j < self.ny else -1

    def _candidates(self, c: int) -> tuple[np.ndarray, np.ndarray]:
        """The sorted candidate ids of cell ``c`` (every segment for -1) and their lower bounds (m)."""
        if c < 0:
            return self._all_ids, self._all_lower
        lo, hi = int(self._offsets[c]), int(self._offsets[c + 1])
        return self._index[lo:hi], self._lower_m[lo:hi]

    def _sector_lists(self, c: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cell ``c``'s candidates for the compiled cast, cached: ``cand`` ``(K, 5)`` nearest first
        as ``[ax, ay, bx − ax, by − ay, lower bound m]``, and per angular sector of the directions
        that can reach them from inside the cell, their positions in ``cand`` (``starts``
        ``(_SECTORS + 1,)`` into ``entries``)."""
        got = self._sector_cache.get(c)
        if got is None:
            ids, lower = self._candidates(c)
            seg = self.segments[ids]
            i, j = divmod(c, self.ny)
            centre = (self.x0 + (i + 0.5) * self.cell_m, self.y0 + (j + 0.5) * self.cell_m)
            bins = _sector_bins(seg, *centre, self.cell_m * math.sqrt(0.5))
            cand = np.column_stack([seg[:, :2], seg[:, 2:] - seg[:, :2], lower])
            starts = np.empty(_SECTORS + 1, np.int64)
            got = (cand, starts, _k.sector_lists(bins, _SECTORS, starts))
            if self._sector_entries + len(got[2]) + len(ids) > _CACHE_ENTRIES:
                self._sector_cache.clear()
                self._sector_entries = 0
            self._sector_cache[c] = got
            self._sector_entries += len(got[2]) + len(ids)
        return got

    def _bands(self, x: float, y: float) -> list[_Band]:
        """The candidate bands of the cell holding ``(x, y)`` (all segments outside the grid)."""
        i = int((x - self.x0) // self.cell_m)
        j = int((y - self.y0) // self.cell_m)
        if not (0 <= i < self.nx and 0 <= j < self.ny):
            return self._all
        c = i * self.ny + j
        bands = self._cache.get(c)
        if bands is None:
            lo, hi = int(self._offsets[c]), int(self._offsets[c + 1])
            bands = []
            size_start = lo
            for b, size in enumerate(_BANDS):
                end = min(hi, size_start + size) if b < len(_BANDS) - 1 else hi
                if end <= size_start:
                    break
                cut = float(self._lower_um[end]) * 1e-6 if end < hi else math.inf
                seg = self.segments[self._index[size_start:end]]
                bins = None
                if b > 0 and end - size_start >= _CULL_MIN:
                    centre = (self.x0 + (i + 0.5) * self.cell_m, self.y0 + (j + 0.5) * self.cell_m)
                    bins = _sector_bins(seg, *centre, self.cell_m * math.sqrt(0.5))
                bands.append(_Band(seg, cut, bins))
                size_start = end
            if len(self._cache) >= _CACHE_CELLS:
                self._cache.clear()
            self._cache[c] = bands
        return bands

    def candidates(self, x: float, y: float) -> np.ndarray:
        """Segments ``(K, 4)`` that a ray from ``(x, y)`` can hit within max range."""
        bands = self._bands(x, y)
        if len(bands) == 1:
            return bands[0].seg
        return np.concatenate([b.seg for b in bands]) if bands else np.zeros((0, 4))

    def cast(self, x: float, y: float, angles_rad: np.ndarray) -> np.ndarray:
        """Ranges ``(B,)`` in metres along world-frame ``angles_rad`` ``(B,)``; no return = max range.

        The compiled loop (:mod:`lfdfuse.world.raycast_kernel`) when it is ready (and the
        process has made its first ``segments._WARMUP_CALLS`` calls), else :meth:`cast_reference`: the
        same values.
        """
        if WARMUP() and _k.cast_sectors_loop.ready():
            c = self._cell(x, y)
            got = self._sector_cache.get(c)
            if got is None and c >= 0 and _k.sector_lists.ready():
                got = self._sector_lists(c)
            if got is not None or c < 0 and _k.cast_loop.ready():
                angles = np.asarray(angles_rad, dtype=np.float64).reshape(-1)
                out = np.empty(angles.shape)
                dx, dy = np.cos(angles), np.sin(angles)
                if got is None:
                    ids, lower, r = self._all_ids, self._all_lower, self.max_range_m
                    _k.cast_loop(self.segments, ids, lower, x, y, dx, dy, r, out)
                else:
                    _k.cast_sectors_loop(*got, x, y, angles, dx, dy, self.max_range_m, out)
                return out
        return self.cast_reference(x, y, angles_rad)

    def cast_reference(self, x: float, y: float, angles_rad: np.ndarray) -> np.ndarray:
        """:meth:`cast` in numpy, band by band: the reference the compiled loop is tested against."""
        angles = np.asarray(angles_rad, dtype=np.float64).reshape(-1)
        best = np.full(angles.shape, np.inf)
        if len(angles) == 0:
            return best
        dirs = np.column_stack([np.cos(angles), np.sin(angles)])
        phi = np.mod(angles, _TWO_PI)
        phi[phi >= _TWO_PI] = 0.0
        active = np.argsort(phi)
        for band in self._bands(x, y):
            if band.bins is not None:
                band = self._facing(band, phi[active])
            if len(band.seg):
                self._cast_band(band, x, y, dirs, phi, active, best)
            if band.cut_m == math.inf:
                break
            active = active[best[active] > band.cut_m]
            if len(active) == 0:
                break
        np.minimum(best, self.max_range_m, out=best)
        # a range of zero (the origin on a wall) is +0.0 whichever of ±0 the order of hits kept
        best += 0.0
        return best

    @staticmethod
    def _facing(band: _Band, phi: np.ndarray) -> _Band:
        """The band's segments in a sector of at least one of the beams at angles ``phi`` in [0, 2π)."""
        assert band.bins is not None
        occupied = np.zeros(2 * _SECTORS, dtype=np.int64)
        sector = np.minimum((phi * (_SECTORS / _TWO_PI)).astype(np.int64), _SECTORS - 1)
        occupied[sector] = 1
        occupied[_SECTORS:] = occupied[:_SECTORS]
        count = np.concatenate([[0], np.cumsum(occupied)])
        return band.subset(count[band.bins[:, 1] + 1] > count[band.bins[:, 0]])

    @staticmethod
    def _cast_band(
        band: _Band,
        x: float,
        y: float,
        dirs: np.ndarray,
        phi: np.ndarray,
        active: np.ndarray,
        best: np.ndarray,
    ) -> None:
        """Lower ``best`` ``(B,)`` by the hits on a band of the beams ``active`` (sorted by ``phi``).

        ``dirs`` ``(B, 2)`` are the beams' unit directions, ``phi`` ``(B,)`` their angles in [0, 2π).
        """
        w = band.seg - np.array([x, y, x, y])  # origin → a, origin → b
        cross = w[:, 0] * band.ey - w[:, 1] * band.ex  # also the numerator of the hit distance
        # the arc the segment covers seen from the origin: counter-clockwise from `first`
        ends = np.arctan2(w[:, 1::2], w[:, 0::2])
        first = np.where(cross >= 0.0, ends[:, 0], ends[:, 1])
        width = np.mod(ends[:, 0] + ends[:, 1] - 2.0 * first, _TWO_PI)
        delta = np.minimum(1e-7 + band.slack / (np.abs(cross) + 1e-300), 4.0)
        first = np.mod(first - delta, _TWO_PI)
        first[first >= _TWO_PI] = 0.0
        # beams inside the arc: a run of the active beams sorted by angle, taken twice round
        sphi = phi[active]
        phi2 = np.concatenate([sphi, sphi + _TWO_PI])
        lo = phi2.searchsorted(first, "left")
        cnt = np.minimum(phi2.searchsorted(first + width + 2.0 * delta, "right") - lo, len(active))
        total = int(cnt.sum())
        if total == 0:
            return
        k = np.repeat(np.arange(len(cnt)), cnt)
        beam = np.concatenate([active, active])[
            np.arange(total) + np.repeat(lo - (np.cumsum(cnt) - cnt), cnt)
        ]
        # the exact solve of `intersect` on those pairs only: the same operations, the same values
        d = dirs[beam]
        dxc, dyc = d[:, 0], d[:, 1]
        ex, ey = band.ex[k], band.ey[k]
        wk = w[k]
        wx, wy = wk[:, 0], wk[:, 1]
        denom = dxc * ey - dyc * ex
        parallel = np.abs(denom) <= _EPS
        inv = 1.0 / np.where(parallel, 1.0, denom)
        t = cross[k] * inv
        u = (wx * dyc - wy * dxc) * inv
        hit = ~parallel & (t >= 0.0) & (u >= -1e-12) & (u <= 1.0 + 1e-12)
        out = np.where(hit, t, np.inf)
        if parallel.any():
            p = np.flatnonzero(parallel)
            out[p] = _collinear(wx[p], wy[p], ex[p], ey[p], dxc[p], dyc[p], out[p])
        np.minimum.at(best, beam, out)

    def clearance(self, x: float, y: float) -> float:
        """Distance (m) from a point to the nearest segment, or max range if none is nearer."""
        if WARMUP() and _k.clearance_loop.ready():
            ids, lower = self._candidates(self._cell(x, y))
            return float(_k.clearance_loop(self.segments, ids, lower, x, y, self.max_range_m))
        return self.clearance_reference(x, y)

    def clearance_reference(self, x: float, y: float) -> float:
        """:meth:`clearance` in numpy, band by band."""
        best = math.inf
        px, py = np.array([x]), np.array([y])
        for band in self._bands(x, y):
            if len(band.seg):
                best = min(best, float(_point_segment_distance(px, py, band.seg).min()))
            if best <= band.cut_m:
                break
        return min(best, self.max_range_m)

    def visible(self, x0: float, y0: float, x1: float, y1: float) -> bool:
        """True when the straight line between two points crosses no segment."""
        dx, dy = x1 - x0, y1 - y0
        dist = math.hypot(dx, dy)
        if dist == 0.0:
            return True
        if WARMUP() and _k.blocked_loop.ready():
            ids, lower = self._candidates(self._cell(x0, y0) if dist <= self.max_range_m else -1)
            return not _k.blocked_loop(self.segments, ids, lower, x0, y0, dx / dist, dy / dist, dist)
        return self.visible_reference(x0, y0, x1, y1)

    def visible_reference(self, x0: float, y0: float, x1: float, y1: float) -> bool:
        """:meth:`visible` in numpy, band by band."""
        dx, dy = x1 - x0, y1 - y0
        dist = math.hypot(dx, dy)
        if dist == 0.0:
            return True
        bands = self._bands(x0, y0) if dist <= self.max_range_m else self._all
        ox, oy = np.array([x0]), np.array([y0])
        ux, uy = np.array([dx / dist]), np.array([dy / dist])
        for band in bands:
            if len(band.seg) and intersect(ox, oy, ux, uy, band.seg).min() < dist:
                return False
            if band.cut_m >= dist:
                break
        return True
