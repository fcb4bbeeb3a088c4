"""The teacher's planner: its grid and fields against brute force, and touring real maps.

Brute force here is a plain Dijkstra (scipy.sparse.csgraph) over the 8-connected free cells
with the planner's documented step costs, and exact point–segment distances from shapely.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from lfdfuse.sources.planner import Planner, PlannerParams, clearance_grid
from lfdfuse.world.model import World, load_world
from tests.conftest import SHARED

MAPS = SHARED / "realdata" / "maps"
RADIUS = 0.25


def centres(p: Planner) -> tuple[np.ndarray, np.ndarray]:
    res = p.params.resolution_m
    gx, gy = np.meshgrid(
        p.x0 + (np.arange(p.nx) + 0.5) * res, p.y0 + (np.arange(p.ny) + 0.5) * res, indexing="ij"
    )
    return gx, gy


def nearest_wall(seg: np.ndarray, gx: np.ndarray, gy: np.ndarray) -> np.ndarray:
    """Exact distance from each point to the nearest segment (shapely's nearest-neighbour tree)."""
    tree = shapely.STRtree(shapely.linestrings(seg.reshape(-1, 2, 2)))
    _, dist = tree.query_nearest(
        shapely.points(gx.ravel(), gy.ravel()), return_distance=True, all_matches=False
    )
    return np.asarray(dist).reshape(gx.shape)


def brute_field(p: Planner, goal: tuple[int, int]) -> np.ndarray:
    """Cost-to-go over the 8-connected cells of the goal's region: a step costs its length × the
    mean step cost."""
    region = p.regions == p.regions[goal]
    idx = -np.ones((p.nx, p.ny), dtype=np.int64)
    cells = np.argwhere(region)
    idx[region] = np.arange(len(cells))
    rows, cols, w = [], [], []
    for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
        a = cells + (di, dj)
        ok = (a[:, 0] >= 0) & (a[:, 0] < p.nx) & (a[:, 1] >= 0) & (a[:, 1] < p.ny)
        src, dst = cells[ok], a[ok]
        ok2 = region[dst[:, 0], dst[:, 1]]
        src, dst = src[ok2], dst[ok2]
        cost = (
            math.hypot(di, dj) * 0.5 * (p.step_cost[src[:, 0], src[:, 1]] + p.step_cost[dst[:, 0], dst[:, 1]])
        )
        rows += [idx[src[:, 0], src[:, 1]]]
        cols += [idx[dst[:, 0], dst[:, 1]]]
        w += [cost]
    r, c, v = np.concatenate(rows), np.concatenate(cols), np.concatenate(w)
    graph = coo_matrix((v, (r, c)), shape=(len(cells), len(cells))).tocsr()
    d = dijkstra(graph, directed=False, indices=int(idx[goal]))
    out = np.full((p.nx, p.ny), np.inf)
    out[region] = d
    return out


def check_planner(world: World, rng: np.random.Generator, goals: int) -> Planner:
    p = Planner(world, robot_radius_m=RADIUS)
    params = p.params
    gx, gy = centres(p)
    exact = nearest_wall(world.segments, gx, gy)
    near = exact <= params.comfort_m
    # clearance: exact where it decides costs and passability, above comfort elsewhere
    assert np.array_equal(p.clearance[near], exact[near]) or np.allclose(
        p.clearance[near], exact[near], atol=1e-12
    )
    assert np.all(p.clearance[~near] > params.comfort_m)
    # free space: passable cells, one 4-connected region holding the start's cell
    assert np.all(exact[p.free] > RADIUS + params.margin_m)
    assert ndimage.label(p.free)[1] == 1
    passable = exact > RADIUS + params.margin_m
    labels, _ = ndimage.label(passable)
    assert np.array_equal(p.free, labels == labels[np.argwhere(p.free)[0][0], np.argwhere(p.free)[0][1]])
    cells = np.argwhere(p.free)
    for k in rng.choice(len(cells), goals, replace=False):
        goal = (int(cells[k, 0]), int(cells[k, 1]))
        fld = p.field(*p.centre(*goal))
        want = brute_field(p, goal)
        assert np.array_equal(np.isfinite(fld), np.isfinite(want))
        fin = np.isfinite(want)
        assert np.allclose(fld[fin], want[fin], rtol=1e-9, atol=1e-9)
        # following the field goes downhill, and reaches the goal
        for s in rng.choice(len(cells), 5):
            x, y = p.centre(*cells[s])
            nx_, ny_ = p.follow(x, y, fld, 9)
            assert fld[p.cell(nx_, ny_)] <= fld[p.cell(x, y)]
        x, y = p.centre(*cells[rng.integers(len(cells))])
        assert p.follow(x, y, fld, p.nx * p.ny) == p.centre(*goal)
    return p


@pytest.mark.parametrize("name", ["building", "tee", "obstacles", "corridor"])
def test_builtin_worlds_match_brute_force(name: str) -> None:
    check_planner(load_world(name), np.random.default_rng(0), 3)


def test_a_robot_in_another_region_tours_its_own() -> None:
    world = load_world("building")
    p = Planner(world, robot_radius_m=RADIUS)
    others = [r for r in range(1, int(p.regions.max()) + 1) if not p.free[p.regions == r].any()]
    assert others  # the building has passable pockets apart from the start's region
    rng = np.random.default_rng(2)
    for r in others:
        cells = np.argwhere(p.regions == r)
        x, y = p.centre(*cells[rng.integers(len(cells))])
        far = p.farthest(x, y)
        assert p.regions[p.cell(*far)] == r
        fld = p.field(*far)
        assert np.isfinite(fld[p.cell(x, y)]) and not np.isfinite(fld[p.free]).any()
        want = brute_field(p, p.cell(*far))
        fin = np.isfinite(want)
        assert np.array_equal(np.isfinite(fld), fin) and np.allclose(
            fld[fin], want[fin], rtol=1e-9, atol=1e-9
        )


def test_farthest_is_the_most_expensive_reachable_cell() -> None:
    p = Planner(load_world("building"), robot_radius_m=RADIUS)
    x, y = 2.0, 2.0
    fld = p.field(x, y)
    fx, fy = p.farthest(x, y)
    assert fld[p.cell(fx, fy)] == np.max(fld[np.isfinite(fld)])


def test_goal_in_a_wall_snaps_to_free_space() -> None:
    world = load_world("corridor")
    p = Planner(world, robot_radius_m=RADIUS)
    ax, ay, bx, by = world.segments[0]
    x, y = (ax + bx) / 2, (ay + by) / 2  # on a wall: the nearest free cell becomes the goal
    fld = p.field(x, y)
    assert np.array_equal(np.isfinite(fld), p.free)
    goal = np.unravel_index(int(np.argmin(fld)), fld.shape)
    assert fld[goal] == 0.0 and math.dist(p.centre(int(goal[0]), int(goal[1])), (x, y)) < 1.0


def test_clearance_grid_is_exact_within_reach() -> None:
    rng = np.random.default_rng(3)
    seg = rng.uniform(0, 10, (40, 4))
    grid = clearance_grid(seg, x0=-1.0, y0=-2.0, resolution_m=0.25, nx=50, ny=56, exact_m=1.0)
    gx, gy = np.meshgrid(
        -1.0 + (np.arange(50) + 0.5) * 0.25, -2.0 + (np.arange(56) + 0.5) * 0.25, indexing="ij"
    )
    exact = nearest_wall(seg, gx, gy)
    near = exact <= 1.0
    assert np.allclose(grid[near], exact[near], atol=1e-12)
    assert np.all(grid[~near] > 1.0)
    # a far estimate is not wildly off: within a few cells of the truth
    assert np.all(np.abs(grid[~near] - exact[~near]) < 4 * 0.25)


def _real(name: str) -> Path:
    path = MAPS / f"{name}.yaml"
    if not path.exists():
        pytest.skip("shared real data not present (../shared/realdata or $LFDFUSE_SHARED)")
    return path


@pytest.mark.parametrize("name", ["willow-2010-02-18-0.10", "mac_1st_floor_final"])
def test_real_maps_tour_far_across_the_largest_region(name: str) -> None:
    world = load_world(str(_real(name)))
    p = check_planner(world, np.random.default_rng(1), 1)
    # a tour: the farthest point from the start, then the farthest from there
    a = p.farthest(*world.start[:2])
    b = p.farthest(*a)
    assert math.dist(a, world.start[:2]) > 10.0 and math.dist(a, b) > 10.0
    assert p.free[p.cell(*a)] and p.free[p.cell(*b)]


@pytest.mark.parametrize("style", ["keep-center", "keep-left"])
def test_style_teacher_drives_on_a_real_office_map(tmp_path: Path, style: str) -> None:
    """keep-left follows its wall into every opening: on Willow one is narrower than the robot."""
    from lfdfuse.sources.simulate import SimulateOptions, simulate
    from lfdfuse.sources.tasks import Leg

    world = load_world(str(_real("willow-2010-02-18-0.10")))
    summary = simulate(
        SimulateOptions(world=world, legs=[Leg(None, style)], teacher_name=style, duration_s=120.0),
        out=tmp_path / "w.mcap",
    )
    assert summary.distance_m >= 10.0 and summary.collisions == 0


def test_planner_params_are_honoured() -> None:
    world = load_world("tee")
    coarse = Planner(world, robot_radius_m=RADIUS, params=PlannerParams(resolution_m=0.4))
    fine = Planner(world, robot_radius_m=RADIUS)
    assert coarse.nx * 2 in (fine.nx, fine.nx + 1) and coarse.ny * 2 in (fine.ny, fine.ny + 1)
