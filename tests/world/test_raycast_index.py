"""The raycast index gives exactly what a brute-force cast over every segment gives.

Brute force = :func:`lfdfuse.world.raycast.intersect` (the exact solve, itself checked against
shapely in test_raycast.py) over all segments, the minimum per beam, clipped to max range.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.world import raycast, segments
from lfdfuse.world.model import load_world
from lfdfuse.world.raycast import RayCaster
from lfdfuse.world.segments import _point_segment_distance, intersect, near_pairs
from tests.conftest import SHARED

MAPS = SHARED / "realdata" / "maps"


@pytest.fixture(autouse=True)
def _compiled_from_the_first_call(monkeypatch: pytest.MonkeyPatch) -> None:
    # cast() runs the compiled loops at once (cast_reference() the numpy bands): both are checked
    monkeypatch.setattr(segments.WARMUP, "left", 0)


def brute_cast(seg: np.ndarray, x: float, y: float, angles: np.ndarray, max_range: float) -> np.ndarray:
    n = len(angles)
    if len(seg) == 0:
        return np.full(n, max_range)
    t = intersect(np.full(n, x), np.full(n, y), np.cos(angles), np.sin(angles), seg)
    return np.minimum(t.min(axis=1), max_range)


def brute_clearance(seg: np.ndarray, x: float, y: float, max_range: float) -> float:
    if len(seg) == 0:
        return max_range
    return min(float(_point_segment_distance(np.array([x]), np.array([y]), seg).min()), max_range)


def brute_visible(seg: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> bool:
    d = math.hypot(x1 - x0, y1 - y0)
    if d == 0 or len(seg) == 0:
        return True
    t = intersect(np.array([x0]), np.array([y0]), np.array([(x1 - x0) / d]), np.array([(y1 - y0) / d]), seg)
    return bool(t.min() >= d)


def box_map(n: int, rng: np.random.Generator, size: tuple[float, float] = (40.0, 30.0)) -> np.ndarray:
    w, h = size
    segs = [[0, 0, w, 0], [w, 0, w, h], [w, h, 0, h], [0, h, 0, 0]]
    while len(segs) < n:
        x, y = rng.uniform(1, w - 2), rng.uniform(1, h - 2)
        a, b = rng.uniform(0.2, 1.5, 2)
        segs += [[x, y, x + a, y], [x + a, y, x + a, y + b], [x + a, y + b, x, y + b], [x, y + b, x, y]]
    return np.asarray(segs[:n], dtype=np.float64)


def check_agrees(
    rc: RayCaster, seg: np.ndarray, rng: np.random.Generator, poses: int, lo: np.ndarray, hi: np.ndarray
) -> None:
    beams = -math.pi / 2 + math.pi / 180 * np.arange(181)
    for _ in range(poses):
        x, y = rng.uniform(lo, hi)
        th = rng.uniform(-math.pi, math.pi)
        want = brute_cast(seg, x, y, beams + th, rc.max_range_m)
        # the compiled caster and its numpy reference
        assert np.array_equal(rc.cast(x, y, beams + th), want)
        assert np.array_equal(rc.cast_reference(x, y, beams + th), want)
        assert (
            rc.clearance(x, y) == rc.clearance_reference(x, y) == brute_clearance(seg, x, y, rc.max_range_m)
        )
        x1, y1 = x + rng.uniform(-9, 9), y + rng.uniform(-9, 9)
        assert (
            rc.visible(x, y, x1, y1) == rc.visible_reference(x, y, x1, y1) == brute_visible(seg, x, y, x1, y1)
        )


@pytest.mark.parametrize(("n", "cell"), [(4, 1.0), (200, 1.0), (1000, 0.7), (6000, 1.0), (6000, 2.5)])
def test_box_maps_agree_exactly_with_brute_force(n: int, cell: float) -> None:
    rng = np.random.default_rng(n)
    seg = box_map(n, rng)
    rc = RayCaster(seg, max_range_m=8.0, cell_m=cell)
    # poses inside and around the map, some outside the grid
    check_agrees(rc, seg, rng, 60, np.array([-12.0, -12.0]), np.array([52.0, 42.0]))


@pytest.mark.parametrize("name", ["building", "obstacles", "tee", "corridor"])
def test_builtin_worlds_agree_exactly_with_brute_force(name: str) -> None:
    world = load_world(name)
    rc = RayCaster(world.segments, max_range_m=8.0)
    x0, y0, x1, y1 = world.bounds()
    check_agrees(
        rc,
        world.segments,
        np.random.default_rng(1),
        150,
        np.array([x0 - 1, y0 - 1]),
        np.array([x1 + 1, y1 + 1]),
    )


@settings(max_examples=300, deadline=None)
@given(
    # millimetre coordinates: collinear beams, shared vertices, poses on walls and at vertices
    segs=st.lists(
        st.tuples(*[st.integers(-4000, 4000).map(lambda v: v / 1000)] * 4), min_size=1, max_size=40
    ),
    pick=st.integers(0, 10_000),
    on_vertex=st.booleans(),
    x=st.integers(-5000, 5000).map(lambda v: v / 1000),
    y=st.integers(-5000, 5000).map(lambda v: v / 1000),
    angles=st.lists(
        st.sampled_from([0.0, math.pi / 2, math.pi, -math.pi / 2, math.pi / 4, -1e-17, 2 * math.pi])
        | st.floats(-10.0, 10.0),
        min_size=1,
        max_size=12,
    ),
    cell=st.sampled_from([0.3, 1.0, 3.0]),
    max_range=st.sampled_from([2.0, 8.0]),
)
def test_degenerate_maps_agree_exactly_with_brute_force(
    segs: list[tuple[float, float, float, float]],
    pick: int,
    on_vertex: bool,
    x: float,
    y: float,
    angles: list[float],
    cell: float,
    max_range: float,
) -> None:
    seg = np.array(segs)  # zero-length segments included
    if on_vertex:
        x, y = float(seg[pick % len(seg), 0]), float(seg[pick % len(seg), 1])
    rc = RayCaster(seg, max_range_m=max_range, cell_m=cell)
    a = np.array(angles)
    want = brute_cast(seg, x, y, a, max_range)
    assert np.array_equal(rc.cast(x, y, a), want) and np.array_equal(rc.cast_reference(x, y, a), want)
    assert rc.clearance(x, y) == rc.clearance_reference(x, y) == brute_clearance(seg, x, y, max_range)
    seen = brute_visible(seg, x, y, x + 1.5, y - 0.5)
    assert rc.visible(x, y, x + 1.5, y - 0.5) == rc.visible_reference(x, y, x + 1.5, y - 0.5) == seen


def test_no_walls_and_no_beams() -> None:
    rc = RayCaster(np.zeros((0, 4)), max_range_m=5.0)
    assert rc.cast(1.0, 2.0, np.array([0.0, 3.0])).tolist() == [5.0, 5.0]
    assert rc.clearance(0.0, 0.0) == 5.0 and rc.visible(0.0, 0.0, 3.0, 3.0)
    one = RayCaster(np.array([[0.0, 0.0, 1.0, 0.0]]))
    assert one.cast(0.5, 1.0, np.zeros(0)).shape == (0,)


def test_near_pairs_finds_exactly_the_cells_within_reach() -> None:
    rng = np.random.default_rng(4)
    seg = box_map(60, rng, size=(12.0, 9.0))
    nx, ny, cell, reach = 30, 25, 0.5, 1.7
    got = set()
    for s, i, j, d in near_pairs(seg, x0=-1.0, y0=-1.0, cell_m=cell, nx=nx, ny=ny, reach_m=reach):
        assert np.all(d <= reach)
        got |= set(zip(s.tolist(), i.tolist(), j.tolist(), strict=True))
    cx = -1.0 + (np.arange(nx) + 0.5) * cell
    cy = -1.0 + (np.arange(ny) + 0.5) * cell
    gx, gy = np.meshgrid(cx, cy, indexing="ij")
    dist = _point_segment_distance(gx.ravel(), gy.ravel(), seg)  # (cells, S)
    c, s = np.nonzero(dist <= reach)
    want = set(zip(s.tolist(), (c // ny).tolist(), (c % ny).tolist(), strict=True))
    assert got == want


def test_agrees_with_shapely_on_a_dense_map() -> None:
    # independent of the shared solve: shapely's own intersection on a map of 3000 segments
    rng = np.random.default_rng(9)
    seg = box_map(3000, rng)
    rc = RayCaster(seg, max_range_m=8.0)
    geom = shapely.MultiLineString([((a, b), (c, d)) for a, b, c, d in seg])
    for _ in range(100):
        x, y, th = rng.uniform(0.5, 39.5), rng.uniform(0.5, 29.5), rng.uniform(-math.pi, math.pi)
        got = float(rc.cast(x, y, np.array([th]))[0])
        ray = shapely.LineString([(x, y), (x + 8 * math.cos(th), y + 8 * math.sin(th))])
        hit = ray.intersection(geom)
        want = 8.0 if hit.is_empty else min(8.0, shapely.distance(shapely.Point(x, y), hit))
        assert got == pytest.approx(want, abs=1e-9)


@pytest.mark.parametrize("name", ["willow-2010-02-18-0.10", "mac_1st_floor_final"])
def test_real_maps_agree_exactly_with_brute_force(name: str) -> None:
    path = MAPS / f"{name}.yaml"
    if not path.exists():
        pytest.skip("shared real data not present (../shared/realdata or $LFDFUSE_SHARED)")
    world = load_world(str(path))
    rc = RayCaster(world.segments, max_range_m=8.0)
    x0, y0, x1, y1 = world.bounds()
    check_agrees(rc, world.segments, np.random.default_rng(2), 40, np.array([x0, y0]), np.array([x1, y1]))


@pytest.mark.parametrize("bands", [(1, 2, 4, 8, 16), (3, 30), (5,)])
def test_tiny_bands_agree_exactly_with_brute_force(
    monkeypatch: pytest.MonkeyPatch, bands: tuple[int, ...]
) -> None:
    # many band boundaries per cell: every early exit is exercised
    monkeypatch.setattr(raycast, "_BANDS", bands)
    rng = np.random.default_rng(len(bands))
    seg = box_map(800, rng)
    rc = RayCaster(seg, max_range_m=8.0, cell_m=1.5)
    check_agrees(rc, seg, rng, 80, np.array([-2.0, -2.0]), np.array([42.0, 32.0]))
