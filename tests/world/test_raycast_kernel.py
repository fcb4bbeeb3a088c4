"""The compiled raycaster gives exactly what the numpy reference gives, and falls back to it.

:meth:`RayCaster.cast` runs the numba loops of :mod:`lfdfuse.world.raycast_kernel` when they
compile; :meth:`RayCaster.cast_reference` (and ``clearance_reference``, ``visible_reference``)
are the numpy bands, themselves checked against brute force in test_raycast_index.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.kernels import jit
from lfdfuse.world import raycast_kernel, segments
from lfdfuse.world.model import load_world
from lfdfuse.world.raycast import RayCaster, near_pairs
from tests.conftest import SHARED

MAPS = SHARED / "realdata" / "maps"


@pytest.fixture(autouse=True)
def _compiled(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(jit.MODE, raising=False)
    monkeypatch.setattr(segments.WARMUP, "left", 0)  # compiled from the first call
    for k in (raycast_kernel.cast_loop, raycast_kernel.cast_sectors_loop, raycast_kernel.sector_lists):
        assert k.ready(), "numba is a dependency: the compiled raycaster must compile here"


def agree(rc: RayCaster, x: float, y: float, angles: np.ndarray, x1: float, y1: float) -> None:
    got, want = rc.cast(x, y, angles), rc.cast_reference(x, y, angles)
    # bit for bit: the same float64 operations on the same pairs
    assert got.tobytes() == want.tobytes(), (x, y, angles[got != want], got[got != want], want[got != want])
    assert rc.clearance(x, y) == rc.clearance_reference(x, y)
    assert rc.visible(x, y, x1, y1) == rc.visible_reference(x, y, x1, y1)


coord = st.integers(-4000, 4000).map(lambda v: v / 1000)  # millimetres: exact collinear walls
wall = st.tuples(coord, coord, coord, coord)
# axis-aligned walls on a few shared lines: collinear runs, beams along walls, shared ends
line = st.sampled_from([-2.0, -0.5, 0.0, 0.25, 1.0, 3.0])
axis_wall = st.one_of(
    st.tuples(line, coord, line, coord).map(lambda t: (t[0], t[1], t[0], t[3])),
    st.tuples(coord, line, coord, line).map(lambda t: (t[0], t[1], t[2], t[1])),
)
point_wall = coord.flatmap(lambda a: coord.map(lambda b: (a, b, a, b)))  # zero length


@settings(max_examples=400, deadline=None)
@given(
    segs=st.lists(st.one_of(wall, axis_wall, point_wall), min_size=1, max_size=120),
    pick=st.integers(0, 10_000),
    where=st.sampled_from(["free", "vertex", "on_wall", "end"]),
    x=coord,
    y=coord,
    beams=st.integers(0, 400),
    spread=st.sampled_from([math.pi, 2 * math.pi, 0.3]),
    theta=st.sampled_from([0.0, math.pi / 2, -math.pi, math.pi / 4, 2 * math.pi]) | st.floats(-10.0, 10.0),
    extra=st.lists(
        st.sampled_from([0.0, math.pi / 2, math.pi, -math.pi / 2, -1e-17, 2 * math.pi]), max_size=6
    ),
    cell=st.sampled_from([0.3, 1.0, 3.0]),
    max_range=st.sampled_from([2.0, 8.0]),
)
def test_random_maps_cast_exactly_as_the_reference(
    segs: list[tuple[float, float, float, float]],
    pick: int,
    where: str,
    x: float,
    y: float,
    beams: int,
    spread: float,
    theta: float,
    extra: list[float],
    cell: float,
    max_range: float,
) -> None:
    seg = np.array(segs)
    s = seg[pick % len(seg)]
    if where == "vertex":
        x, y = float(s[0]), float(s[1])
    elif where == "on_wall":  # the origin on a wall (the midpoint, exact in millimetres / 2)
        x, y = float((s[0] + s[2]) / 2), float((s[1] + s[3]) / 2)
    elif where == "end":  # beams through a segment end
        extra = [*extra, math.atan2(s[1] - y, s[0] - x), math.atan2(s[3] - y, s[2] - x)]
    angles = theta + np.linspace(-spread / 2, spread / 2, beams) if beams else np.zeros(0)
    angles = np.concatenate([angles, np.array(extra, dtype=np.float64)])
    rc = RayCaster(seg, max_range_m=max_range, cell_m=cell)
    agree(rc, x, y, angles, x + 1.5, y - 0.5)
    agree(rc, x, y, angles, float(s[2]), float(s[3]))
    agree(rc, x + 40.0, y, angles, x, y)  # outside the grid: every segment


@pytest.mark.parametrize("name", ["building", "obstacles", "tee", "corridor"])
def test_builtin_worlds_cast_exactly_as_the_reference(name: str) -> None:
    world = load_world(name)
    rc = RayCaster(world.segments, max_range_m=8.0)
    x0, y0, x1, y1 = world.bounds()
    rng = np.random.default_rng(3)
    beams = np.linspace(-math.pi / 2, math.pi / 2, 181)
    for _ in range(200):
        x, y = rng.uniform([x0 - 1, y0 - 1], [x1 + 1, y1 + 1])
        agree(rc, x, y, beams + rng.uniform(-math.pi, math.pi), *rng.uniform([x0, y0], [x1, y1]))


@pytest.mark.parametrize("name", ["willow-2010-02-18-0.10", "mac_1st_floor_final"])
def test_real_maps_cast_exactly_as_the_reference(name: str) -> None:
    path = MAPS / f"{name}.yaml"
    if not path.exists():
        pytest.skip("shared real data not present (../shared/realdata or $LFDFUSE_SHARED)")
    world = load_world(str(path))
    rc = RayCaster(world.segments, max_range_m=8.0)
    x0, y0, x1, y1 = world.bounds()
    rng = np.random.default_rng(5)
    beams = np.linspace(-math.pi / 2, math.pi / 2, 181)
    for _ in range(120):
        x, y = rng.uniform([x0, y0], [x1, y1])
        agree(rc, x, y, beams + rng.uniform(-math.pi, math.pi), *rng.uniform([x0, y0], [x1, y1]))
    # poses on the map's own wall ends: beams along and off walls that share them
    for a in world.segments[rng.choice(len(world.segments), 40, replace=False)]:
        agree(
            rc,
            float(a[0]),
            float(a[1]),
            beams + math.atan2(a[3] - a[1], a[2] - a[0]),
            float(a[2]),
            float(a[3]),
        )


def test_numpy_mode_runs_the_reference(monkeypatch: pytest.MonkeyPatch) -> None:
    rc = RayCaster(np.array([[2.0, -1.0, 2.0, 1.0]]), max_range_m=8.0)
    called: list[str] = []
    real = RayCaster.cast_reference

    def spy(self: RayCaster, x: float, y: float, angles: np.ndarray) -> np.ndarray:
        called.append("reference")
        return real(self, x, y, angles)

    monkeypatch.setattr(RayCaster, "cast_reference", spy)
    rc.cast(0.0, 0.0, np.array([0.0]))
    assert called == []
    monkeypatch.setenv(jit.MODE, "numpy")
    assert rc.cast(0.0, 0.0, np.array([0.0, math.pi])).tolist() == [2.0, 8.0]
    assert called == ["reference"]


def test_a_kernel_that_does_not_compile_warns_once_and_runs_the_reference(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    broken = jit.Kernel(raycast_kernel._cast_loop, signature="void(float64, int32)")  # wrong types
    with pytest.warns(RuntimeWarning) as caught:
        assert not broken.ready()
        assert not broken.ready()  # failed once: not tried (nor warned about) again
    assert len(caught) == 1
    text = str(caught[0].message)
    assert text.startswith("kernel _cast_loop did not compile (") and "\n" not in text
    assert text.endswith("running its numpy reference")
    # the caster then runs its reference: the same ranges
    monkeypatch.setattr(raycast_kernel, "cast_sectors_loop", broken)
    rc = RayCaster(load_world("building").segments, max_range_m=8.0)
    beams = np.linspace(-math.pi / 2, math.pi / 2, 181)
    assert rc.cast(3.0, 3.0, beams).tobytes() == rc.cast_reference(3.0, 3.0, beams).tobytes()


@pytest.mark.parametrize(("n", "cell", "reach"), [(300, 1.0, 8.7), (2000, 0.2, 1.2), (5, 3.0, 0.5)])
def test_the_compiled_index_pairs_are_the_reference_pairs(
    monkeypatch: pytest.MonkeyPatch, n: int, cell: float, reach: float
) -> None:
    rng = np.random.default_rng(n)
    seg = rng.uniform(0, 30, (n, 4))
    seg[: n // 10, 2:] = seg[: n // 10, :2]  # zero-length segments
    kw = {
        "x0": -9.0,
        "y0": -9.0,
        "cell_m": cell,
        "nx": int(48 / cell),
        "ny": int(40 / cell),
        "reach_m": reach,
    }
    got = [np.concatenate(c) for c in zip(*near_pairs(seg, **kw), strict=True)]
    monkeypatch.setenv(jit.MODE, "numpy")
    want = [np.concatenate(c) for c in zip(*near_pairs(seg, **kw), strict=True)]
    assert len(got[0]) > 0
    for a, b in zip(got, want, strict=True):
        assert a.tobytes() == b.astype(a.dtype).tobytes()


def test_a_process_casts_in_numpy_until_the_compiled_loops_pay(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(segments.WARMUP, "left", 3)
    used: list[str] = []
    real = RayCaster.cast_reference

    def spy(self: RayCaster, x: float, y: float, angles: np.ndarray) -> np.ndarray:
        used.append("numpy")
        return real(self, x, y, angles)

    monkeypatch.setattr(RayCaster, "cast_reference", spy)
    rc = RayCaster(np.array([[2.0, -1.0, 2.0, 1.0]]), max_range_m=8.0)
    got = [rc.cast(0.0, 0.0, np.array([0.0, 0.1])).tobytes() for _ in range(6)]
    assert used == ["numpy"] * 3 and len(set(got)) == 1


def test_a_shared_caster_is_built_once_per_map() -> None:
    seg = load_world("building").segments
    rc = RayCaster.shared(seg, max_range_m=8.0)
    assert RayCaster.shared(seg.copy(), max_range_m=8.0) is rc
    assert RayCaster.shared(seg, max_range_m=5.0) is not rc
    assert RayCaster.shared(seg[1:], max_range_m=8.0) is not rc
    beams = np.linspace(-math.pi / 2, math.pi / 2, 181)
    assert (
        rc.cast(3.0, 3.0, beams).tobytes() == RayCaster(seg, max_range_m=8.0).cast(3.0, 3.0, beams).tobytes()
    )


def _twice(x: float) -> float:
    return 2.0 * x


def _twice_plus_one(x: float) -> float:
    return _twice(x) + 1.0


def _twice_plus_two(x: float) -> float:
    return _twice(x) + 2.0


def test_a_helper_is_compiled_with_the_loops_that_call_it() -> None:
    """One solve serves every loop: ``kernel(loop, calls=[helper])`` compiles the helper with the
    loop; without it a loop calling a plain function does not compile (its reference runs)."""
    eager = "float64(float64)"  # compiled in ready(), as the loops are on their first call
    with_helper = jit.Kernel(_twice_plus_one, signature=eager, calls=[_twice])
    assert with_helper.ready() and with_helper(3.0) == 7.0
    assert _twice(3.0) == 6.0 and not hasattr(_twice, "py_func")  # the module keeps the plain helper
    with pytest.warns(RuntimeWarning, match="kernel _twice_plus_two did not compile"):
        assert not jit.Kernel(_twice_plus_two, signature=eager).ready()
    with pytest.warns(RuntimeWarning, match="calls no _twice"):  # a helper the loop does not call
        assert not jit.Kernel(_twice, calls=[_twice]).ready()
    for loop in (raycast_kernel.cast_loop, raycast_kernel.cast_sectors_loop, raycast_kernel.blocked_loop):
        assert loop.calls == (raycast_kernel._solve,)
