"""World benchmarks: raycasting on large maps, the planner's setup, simulation on real building maps.

Each row has a rate beside a baseline measured in the same run, and their ratio:

- laser scans (181 beams, 8 m) per second on box maps of 200, 1,000 and 20,000 segments and on
  the real maps: the compiled caster against its numpy reference (the ratio), and beside them the
  previous raycaster (a grid whose cells list every segment within range, each scan solving every
  beam against every candidate);
- the planner's setup on the real maps, against computing every cell's clearance from every
  segment (the previous planner's cells × segments setup);
- ``simulate`` with a style teacher on the real maps: simulated steps per second with the
  compiled kernels against the numpy references (the ratio), timed after a short first run in
  the same world (as every run after a process's first: the map's raycast index built, the
  kernels loaded; that first run's seconds are a column of their own), their multiple of real
  time (10 steps per second), with the distance the teacher drove.

The real maps are read from ``../shared/realdata/maps`` beside the checkout (or
``$LFDFUSE_SHARED``); without them those rows are left out.

    python -m tests.bench.world [--quick]
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from lfdfuse.sim.sensors import LaserParams
from lfdfuse.sources.planner import Planner, PlannerParams
from lfdfuse.world.model import World, load_world
from lfdfuse.world.raycast import RayCaster
from lfdfuse.world.segments import _point_segment_distance, intersect
from tests.bench.pipeline import box_map, numpy_kernels, rate, simulate_rate

Row = dict[str, object]

REAL_MAPS = ("willow-2010-02-18-0.10", "mac_1st_floor_final")


def shared_maps() -> Path:
    """Where the real maps are: $LFDFUSE_SHARED/realdata/maps, else ../shared beside the checkout."""
    shared = os.environ.get("LFDFUSE_SHARED")
    root = Path(shared) if shared else Path(__file__).resolve().parents[2].parent / "shared"
    return root / "realdata" / "maps"


class _PreviousCaster:
    """The previous raycaster: per 1 m cell, every segment within range; every beam × candidate."""

    def __init__(self, segments: np.ndarray, *, max_range_m: float = 8.0, cell_m: float = 1.0) -> None:
        self.segments, self.max_range_m, self.cell_m = segments, max_range_m, cell_m
        self.x0 = float(segments[:, [0, 2]].min()) - max_range_m
        self.y0 = float(segments[:, [1, 3]].min()) - max_range_m
        self.nx = math.ceil((float(segments[:, [0, 2]].max()) + max_range_m - self.x0) / cell_m)
        self.ny = math.ceil((float(segments[:, [1, 3]].max()) + max_range_m - self.y0) / cell_m)
        reach = max_range_m + cell_m * math.sqrt(0.5)
        cx = self.x0 + (np.arange(self.nx) + 0.5) * cell_m
        cy = self.y0 + (np.arange(self.ny) + 0.5) * cell_m
        gx, gy = np.meshgrid(cx, cy, indexing="ij")
        px, py = gx.ravel(), gy.ravel()
        self.lists: list[np.ndarray] = []
        chunk = max(1, 2_000_000 // len(segments))
        for i in range(0, len(px), chunk):
            d = _point_segment_distance(px[i : i + chunk], py[i : i + chunk], segments)
            self.lists.extend(segments[np.nonzero(row <= reach)[0]] for row in d)

    def cast(self, x: float, y: float, angles: np.ndarray) -> np.ndarray:
        i, j = int((x - self.x0) // self.cell_m), int((y - self.y0) // self.cell_m)
        seg = self.lists[i * self.ny + j] if 0 <= i < self.nx and 0 <= j < self.ny else self.segments
        if len(seg) == 0:
            return np.full(angles.shape, self.max_range_m)
        n = len(angles)
        t = intersect(np.full(n, x), np.full(n, y), np.cos(angles), np.sin(angles), seg)
        return np.asarray(np.minimum(t.min(axis=1), self.max_range_m))


def _free_poses(rc: RayCaster, segments: np.ndarray, n: int, seed: int) -> np.ndarray:
    """``n`` poses ``(x, y, θ)`` at least a robot radius from every wall."""
    rng = np.random.default_rng(seed)
    lo, hi = segments.reshape(-1, 2).min(axis=0), segments.reshape(-1, 2).max(axis=0)
    out: list[tuple[float, float, float]] = []
    while len(out) < n:
        x, y = rng.uniform(lo, hi)
        if rc.clearance(x, y) > 0.25:
            out.append((x, y, rng.uniform(-math.pi, math.pi)))
    return np.array(out)


def bench_raycast(name: str, segments: np.ndarray, *, quick: bool) -> Row:
    angles = LaserParams().geometry.angles
    rc = RayCaster(segments, max_range_m=8.0)
    old = _PreviousCaster(segments, max_range_m=8.0)
    poses = _free_poses(rc, segments, 200, seed=1)
    for x, y, th in poses[:20]:  # all agree: a benchmark of the same answers
        got = rc.cast(x, y, angles + th)
        if not (
            np.array_equal(got, old.cast(x, y, angles + th))
            and np.array_equal(got, rc.cast_reference(x, y, angles + th))
        ):
            raise AssertionError(f"raycasters disagree on {name}")

    def new() -> int:
        for x, y, th in poses:
            rc.cast(x, y, angles + th)
        return len(poses)

    def reference() -> int:
        with numpy_kernels():
            return new()

    def previous() -> int:
        for x, y, th in poses[:20]:
            old.cast(x, y, angles + th)
        return 20

    new()  # warm the per-cell caches, as a running simulation has
    reference()
    min_s = 0.3 if quick else 1.5
    fast, ref, base = rate(new, min_s=min_s), rate(reference, min_s=min_s), rate(previous, min_s=min_s)
    return {
        "name": f"laser scans, {name} ({len(segments):,} segments)",
        "rate": fast,
        "unit": "scans/s",
        "baseline": "numpy reference",
        "baseline_rate": ref,
        "ratio": fast / ref,
        "previous_rate": base,
    }


def _all_cells_clearance(world: World, res: float) -> np.ndarray:
    """The previous planner's setup: every cell centre against every segment."""
    x0, y0, x1, y1 = world.bounds()
    nx, ny = math.ceil((x1 - x0) / res), math.ceil((y1 - y0) / res)
    gx, gy = np.meshgrid(x0 + (np.arange(nx) + 0.5) * res, y0 + (np.arange(ny) + 0.5) * res, indexing="ij")
    px, py = gx.ravel(), gy.ravel()
    out = np.empty(len(px))
    chunk = max(1, 2_000_000 // len(world.segments))
    for i in range(0, len(px), chunk):
        out[i : i + chunk] = _point_segment_distance(
            px[i : i + chunk], py[i : i + chunk], world.segments
        ).min(1)
    return out


def bench_planner(world: World) -> Row:
    t0 = time.perf_counter()
    Planner(world, robot_radius_m=0.25)
    new = time.perf_counter() - t0
    t0 = time.perf_counter()
    _all_cells_clearance(world, PlannerParams().resolution_m)
    old = time.perf_counter() - t0
    return {
        "name": f"planner setup, {world.name} ({len(world.segments):,} segments)",
        "rate": 1.0 / new,
        "unit": "setups/s",
        "baseline": "clearance of every cell from every segment",
        "baseline_rate": 1.0 / old,
        "ratio": old / new,
    }


def bench_simulate(world: World, *, style: str, duration_s: float) -> Row:
    from lfdfuse.sources.simulate import SimulateOptions
    from lfdfuse.sources.tasks import Leg

    opts = SimulateOptions(world=world, legs=[Leg(None, style)], teacher_name=style, duration_s=duration_s)
    fast, ref, summary, first_s = simulate_rate(opts)
    return {
        "name": f"simulate {style} {duration_s:g} s, {world.name}",
        "rate": fast,
        "unit": "steps/s",
        "baseline": "numpy kernels",
        "baseline_rate": ref,
        "ratio": fast / ref,
        "x_realtime": fast / 10.0,
        "first_run_s": first_s,
        "distance_m": summary.distance_m,
        "collisions": summary.collisions,
    }


def run(quick: bool) -> list[Row]:
    """Run the world benchmarks and return their rows."""
    rows = [bench_raycast("box hall", box_map(n), quick=quick) for n in (200, 1000, 20_000)]
    folder = shared_maps()
    worlds = [load_world(str(folder / f"{m}.yaml")) for m in REAL_MAPS if (folder / f"{m}.yaml").exists()]
    for world in worlds:
        rows.append(bench_raycast(world.name, world.segments, quick=quick))
    for world in worlds:
        rows.append(bench_planner(world))
    for world in worlds:
        for style in ("keep-right",) if quick else ("keep-right", "keep-center"):
            rows.append(bench_simulate(world, style=style, duration_s=30.0 if quick else 120.0))
    return rows


def render(rows: list[Row]) -> str:
    """A plain text table of the rows."""
    head = ["name", "rate", "unit", "baseline", "baseline_rate", "ratio", "distance_m"]

    def cell(v: object) -> str:
        if isinstance(v, float):
            return f"{v:,.0f}" if abs(v) >= 100 else f"{v:.3g}"
        return "" if v is None else str(v)

    table = [head] + [[cell(r.get(k)) for k in head] for r in rows]
    widths = [max(len(line[i]) for line in table) for i in range(len(head))]
    return "\n".join(
        "  ".join(c.ljust(w) for c, w in zip(line, widths, strict=True)).rstrip() for line in table
    )


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    sys.stdout.write(render(run(quick="--quick" in args)) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
