"""Pipeline benchmarks: speed of every stage, each beside a baseline measured in the same run.

Ratios to the in-run baseline are what to compare across machines; absolute rates depend on a
shared, noisy machine. :mod:`tests.bench.run` runs these with the other suites.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import orjson
import shapely
from shapely.geometry import LineString, Point

from lfdfuse.kernels import jit
from lfdfuse.log import messages as msg
from lfdfuse.sim.loop import RunSummary
from lfdfuse.sim.sensors import LaserParams
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world import segments
from lfdfuse.world.model import load_world
from lfdfuse.world.raycast import RayCaster

# the benchmarks time the compiled loops from the first call (a process otherwise answers its
# first calls with the numpy references, as a short CLI run does)
segments.WARMUP.left = 0


@dataclass(frozen=True)
class Row:
    name: str
    rate: float
    unit: str
    baseline: str
    baseline_rate: float
    target: float | None = None

    @property
    def ratio(self) -> float:
        return self.rate / self.baseline_rate if self.baseline_rate > 0 else math.inf


def rate(fn: Callable[[], int], *, min_s: float = 1.0) -> float:
    """Items per second of ``fn`` (which returns how many items it did), over at least ``min_s``."""
    done, t0 = 0, time.perf_counter()
    while True:
        done += fn()
        el = time.perf_counter() - t0
        if el >= min_s:
            return done / el


@contextlib.contextmanager
def numpy_kernels() -> Iterator[None]:
    """Run the numpy references of the compiled kernels (``LFDFUSE_KERNELS=numpy``) within."""
    before = os.environ.get(jit.MODE)
    os.environ[jit.MODE] = "numpy"
    try:
        yield
    finally:
        if before is None:
            del os.environ[jit.MODE]
        else:
            os.environ[jit.MODE] = before


def simulate_rate(opts: SimulateOptions) -> tuple[float, float, RunSummary, float]:
    """Steps per second of ``simulate`` with the compiled kernels and with the numpy references
    (the same steps: the same bytes are written), the compiled run's summary, and the seconds of
    the process's first (0.5 s) run in this world: the map's index built, the kernels loaded."""
    rates = []
    summaries = []
    first = []
    with tempfile.TemporaryDirectory() as d:
        for numpy in (False, True):
            with numpy_kernels() if numpy else contextlib.nullcontext():
                # warm: the compiled kernels loaded from their cache and the map's index built,
                # as for every run after a process's first in this world
                t0 = time.perf_counter()
                simulate(dataclasses.replace(opts, duration_s=0.5), out=Path(d) / "w.mcap")
                first.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                s = simulate(opts, out=Path(d) / f"{numpy}.mcap")
                rates.append(s.steps / (time.perf_counter() - t0))
                summaries.append(s)
    return rates[0], rates[1], summaries[0], first[0]


def box_map(n_segments: int, seed: int = 0) -> np.ndarray:
    """A 40 × 30 m hall with axis-aligned boxes: about ``n_segments`` segments."""
    rng = np.random.default_rng(seed)
    segs: list[list[float]] = [[0, 0, 40, 0], [40, 0, 40, 30], [40, 30, 0, 30], [0, 30, 0, 0]]
    while len(segs) < n_segments:
        x, y = rng.uniform(1, 38), rng.uniform(1, 28)
        w, h = rng.uniform(0.2, 1.5), rng.uniform(0.2, 1.5)
        segs += [[x, y, x + w, y], [x + w, y, x + w, y + h], [x + w, y + h, x, y + h], [x, y + h, x, y]]
    return np.asarray(segs[:n_segments], dtype=np.float64)


def naive_cast(
    geom: shapely.Geometry, x: float, y: float, angles: np.ndarray, max_range: float
) -> np.ndarray:
    """Per-ray shapely intersection: the straightforward raycaster."""
    out = np.empty(len(angles))
    origin = Point(x, y)
    for i, a in enumerate(angles):
        ray = LineString([(x, y), (x + max_range * math.cos(a), y + max_range * math.sin(a))])
        hit = ray.intersection(geom)
        out[i] = max_range if hit.is_empty else min(max_range, origin.distance(hit))
    return out


def bench_raycast(rows: list[Row]) -> None:
    angles = LaserParams().geometry.angles
    for n in (50, 200, 1000):
        segs = box_map(n)
        rc = RayCaster(segs, max_range_m=8.0)
        geom = shapely.MultiLineString([((a, b), (c, d)) for a, b, c, d in segs])
        rng = np.random.default_rng(1)
        poses = rng.uniform([1, 1, -np.pi], [39, 29, np.pi], (500, 3))

        def fast() -> int:
            for x, y, th in poses:
                rc.cast(x, y, angles + th)
            return len(poses)

        def naive() -> int:
            for x, y, th in poses[:3]:
                naive_cast(geom, x, y, angles + th, 8.0)
            return 3

        rows.append(
            Row(
                f"laser scans, {n} segments",
                rate(fast),
                "scans/s",
                "per-ray shapely",
                rate(naive, min_s=0.5),
                5000.0 if n == 200 else None,
            )
        )


def bench_simulate(rows: list[Row]) -> None:
    world = load_world("building")
    opts = SimulateOptions(
        world=world, legs=[Leg(None, "keep-left")], teacher_name="keep-left", duration_s=120.0, seed=1
    )
    fast, ref, _, _ = simulate_rate(opts)
    rows.append(Row("simulate building, all sensors + MCAP", fast, "steps/s", "numpy kernels", ref, 5000.0))


def bench_encoding(rows: list[Row]) -> None:
    rng = np.random.default_rng(0)
    geom = LaserParams().geometry
    scans = rng.uniform(0, 8, (200, 181))

    def with_orjson() -> int:
        for r in scans:
            orjson.dumps(msg.laser_scan(0, r, geom))
        return len(scans)

    def with_json_full() -> int:
        for r in scans:
            m = msg.laser_scan(0, r, geom)
            m["ranges"] = r.tolist()
            json.dumps(m).encode()
        return len(scans)

    rows.append(
        Row(
            "scan JSON encoding (orjson, mm)",
            rate(with_orjson, min_s=0.5),
            "msgs/s",
            "json, full precision",
            rate(with_json_full, min_s=0.5),
        )
    )


def _demo(folder: Path, seconds: float) -> Path:
    """A keep-left building tour of ``seconds`` (the 10-minute demo of the stage benches)."""
    out = folder / f"demo{int(seconds)}.mcap"
    if not out.exists():
        opts = SimulateOptions(
            world=load_world("building"),
            legs=[Leg(None, "keep-left")],
            teacher_name="keep-left",
            duration_s=seconds,
            seed=2,
        )
        simulate(opts, out=out)
    return out


def bench_behaviors(rows: list[Row], folder: Path) -> None:
    from lfdfuse.behaviors.primitives import compute, resolve_behaviors
    from lfdfuse.log.reader import read_run
    from lfdfuse.segment.demo import observations_of

    run = read_run(_demo(folder, 600.0))
    obs = observations_of(run)
    for preset, target in (("scenario3", 20000.0), ("full", None)):
        names = resolve_behaviors(preset, obs.target_names)

        def whole() -> int:
            compute(obs, names)
            return len(run)

        def per_scan() -> int:
            for k in range(200):
                one = type(obs)(
                    obs.ranges_m[k : k + 1],
                    obs.geometry,
                    None if obs.sonar_m is None else obs.sonar_m[k : k + 1],
                    obs.sonar_angles_rad,
                    obs.sonar_max_m,
                    obs.target_names,
                    obs.target_bearing_rad[k : k + 1],
                    obs.target_range_m[k : k + 1],
                )
                compute(one, names)
            return 200

        compute(obs, names)  # the compiled loops loaded (or compiled) outside the timing
        live = rate(per_scan)
        with numpy_kernels():
            whole_ref, live_ref = rate(whole), rate(per_scan)
        rows.append(
            Row(
                f"behaviour outputs, {preset}, whole log",
                rate(whole),
                "scans/s",
                "per-scan loop",
                live,
                target,
            )
        )
        rows.append(
            Row(f"behaviour outputs, {preset}, whole log", rate(whole), "scans/s", "numpy kernels", whole_ref)
        )
        rows.append(
            Row(f"behaviour outputs, {preset}, per scan (live)", live, "scans/s", "numpy kernels", live_ref)
        )


def bench_segment(rows: list[Row], folder: Path) -> None:
    from lfdfuse.segment.pipeline import segment_file

    src = _demo(folder, 600.0)
    t0 = time.perf_counter()
    segment_file(src, out=folder / "demo600.seg.mcap")
    el = time.perf_counter() - t0
    rows.append(Row("segment end to end, 10-minute demo", 600.0 / el, "x realtime", "real time", 1.0))
    rows.append(Row("segment end to end, 10-minute demo (s)", el, "s", "-", 0.0))


def bench_pf(rows: list[Row], folder: Path) -> None:
    from lfdfuse.estimate.paper import PFParams, reference_step, step

    k, m, n = 30, 1000, 6
    p = PFParams(particles=m)
    rng = np.random.default_rng(0)
    s0 = rng.uniform(0, 1, (k, m, n))
    v = rng.normal(0, 0.5, (n, 2))
    vr = np.array([1.0, 0.0])
    noise = rng.standard_normal((k, m, n))
    u = rng.uniform(0, 1, k)
    state = {"s": s0, "w": np.zeros((k, m))}

    def fast() -> int:
        # fresh random numbers each step, as in the filter (their cost is part of the rate)
        nz = rng.standard_normal((k, m, n))
        uu = rng.uniform(0, 1, k)
        state["s"], state["w"], _ = step(state["s"], state["w"], v, vr, nz, uu, 0.01, p)
        return k * m

    small = (s0[:1, :200], np.zeros((1, 200)), noise[:1, :200], u[:1])

    def naive() -> int:
        reference_step(small[0], small[1], v, vr, small[2], small[3], 0.01, p)
        return 200

    a = step(small[0], small[1], v, vr, small[2], small[3], 0.01, p)
    b = reference_step(small[0], small[1], v, vr, small[2], small[3], 0.01, p)
    assert all(np.allclose(x, y) for x, y in zip(a, b, strict=True)), "vectorised and naive steps disagree"
    rows.append(
        Row(
            "particle filter, N=6, M=1000, K=30",
            rate(fast),
            "particle-steps/s",
            "per-particle Python loop",
            rate(naive),
            8e6,
        )
    )


@contextlib.contextmanager
def reference_kernels() -> Iterator[None]:
    """Run the numpy references of every compiled kernel inside the block (``LFDFUSE_KERNELS``)."""
    from lfdfuse.kernels.jit import MODE

    old = os.environ.get(MODE)
    os.environ[MODE] = "numpy"
    try:
        yield
    finally:
        if old is None:
            del os.environ[MODE]
        else:
            os.environ[MODE] = old


def bench_likelihood(rows: list[Row], folder: Path) -> None:
    """The pf sampler's likelihood statistic (``sum_cos``): compiled beside its numpy reference."""
    from lfdfuse.estimate.kernels import SUM_COS, sum_cos_reference
    from lfdfuse.estimate.model import row_data, sum_cos

    rng = np.random.default_rng(0)
    t, n, p = 600, 6, 384 * 30  # a row of a 10-minute demo, the paper's K=30 trials
    data = row_data(rng.normal(0, 0.6, (t, n, 2)), rng.normal(0, 1, (t, 2)))
    w = rng.dirichlet(np.full(n, 0.5), p)
    SUM_COS.ready()  # compile (or load the cache) outside the timing
    got, want = sum_cos(data, w), sum_cos_reference(data, w)
    assert np.allclose(got, want, rtol=0.0, atol=1e-12), "compiled and reference likelihoods disagree"

    def fast() -> int:
        sum_cos(data, w)
        return t * p

    def reference() -> int:
        sum_cos_reference(data, w)
        return t * p

    rows.append(
        Row(
            "pf likelihood (sum_cos), T=600, n=6, P=11,520",
            rate(fast),
            "particle-steps/s",
            "numpy reference (BLAS)",
            rate(reference),
        )
    )
    bench_discrete_likelihood(rows, rng)


def bench_discrete_likelihood(rows: list[Row], rng: np.random.Generator) -> None:
    """The discrete command model's likelihood (a keyboard demo's decisions): compiled beside
    its numpy reference, which it must equal to the bit."""
    from lfdfuse.estimate.discrete_kernels import DISCRETE_BLOCK, discrete_log_marginal_reference
    from lfdfuse.estimate.model import DiscreteRowData, FusionModel, discrete_log_marginal

    t, n, p = 300, 6, 384 * 4  # a row of a few minutes' keypresses, a discrete pass's particles
    lo = rng.uniform(-math.pi, math.pi, t)
    data = DiscreteRowData(
        rng.normal(0, 0.6, (t, n)), rng.normal(0, 0.6, (t, n)), lo, lo + rng.uniform(0.2, 2.0, t), 5
    )
    w = rng.dirichlet(np.full(n, 0.5), p)
    m = FusionModel()
    DISCRETE_BLOCK.ready()  # compile (or load the cache) outside the timing
    got, want = discrete_log_marginal(data, w, m), discrete_log_marginal_reference(data, w, m)
    assert np.allclose(got, want, rtol=1e-12, atol=0.0), "compiled and reference likelihoods disagree"
    same = got.tobytes() == want.tobytes()

    def fast() -> int:
        discrete_log_marginal(data, w, m)
        return t * p

    def reference() -> int:
        discrete_log_marginal_reference(data, w, m)
        return t * p

    rows.append(
        Row(
            f"pf likelihood (discrete), T=300, n=6, P=1,536{'' if same else ' (bits differ!)'}",
            rate(fast),
            "particle-steps/s",
            "numpy reference",
            rate(reference),
        )
    )


def bench_estimate(rows: list[Row], folder: Path, quick: bool = False) -> None:
    from lfdfuse.estimate.pipeline import EstimateOptions
    from lfdfuse.learn import LearnOptions, learn
    from lfdfuse.network.table import write_table
    from lfdfuse.segment.pipeline import segment_file

    seg = folder / "demo600.seg.mcap"
    if not seg.exists():
        segment_file(_demo(folder, 600.0), out=seg)

    def timed(trials: int, out: Path) -> float:
        t0 = time.perf_counter()
        write_table(learn([seg], options=LearnOptions(EstimateOptions(trials=trials))).table, out)
        return time.perf_counter() - t0

    for trials in (1, 30):
        fast = timed(trials, folder / "f.yaml")
        ref, same = math.inf, True
        if not quick or trials == 1:  # the numpy reference of K=30 takes minutes
            with reference_kernels():
                ref = timed(trials, folder / "f_ref.yaml")
            same = (folder / "f.yaml").read_bytes() == (folder / "f_ref.yaml").read_bytes()
        rows.append(Row(f"estimate end to end, 10-minute demo, K={trials} (s)", fast, "s", "-", 0.0))
        rows.append(
            Row(
                f"estimate, 10-minute demo, K={trials}{'' if same else ' (tables differ!)'}",
                600.0 / fast,
                "x realtime",
                "numpy reference kernels",
                600.0 / ref,
            )
        )


def bench_execute(rows: list[Row], folder: Path) -> None:
    """``execute`` of a table learned from a three-goal tour, against ``simulate`` of the same
    task's teacher (its first run in the process, as a command runs it, and reruns, the map's
    setup done), and against itself with the numpy reference kernels. The reruns
    alternate, two rounds, the best of each kept: on a shared machine a rate measured minutes
    apart from its baseline says more about the load than the code."""
    from lfdfuse.execute.run import ExecuteOptions, run_table
    from lfdfuse.learn import demonstrate, learn

    world = load_world("building")
    legs = [Leg("red", "keep-left"), Leg("green", "keep-center"), Leg("blue", "keep-right")]
    demo = demonstrate(legs, world=world, folder=folder, name="task", duration_s=400.0, seed=1)
    table = learn([demo.segmented]).table
    sim_opts = SimulateOptions(world=world, legs=legs, teacher_name="task", duration_s=400.0, seed=1)

    def sim() -> float:
        t0 = time.perf_counter()
        s = simulate(sim_opts, out=folder / "sim.mcap")
        return s.steps / (time.perf_counter() - t0)

    def execute(numpy: bool = False) -> float:
        with numpy_kernels() if numpy else contextlib.nullcontext():
            t0 = time.perf_counter()
            r = run_table(
                ExecuteOptions(world=world, table=table, max_time_s=300.0),
                out=folder / "run.mcap",
                command="execute",
            )
            return r.summary.steps / (time.perf_counter() - t0)

    rates: dict[str, list[float]] = {"sim": [], "exec": [], "ref": []}
    for _ in range(2):
        rates["sim"].append(sim())
        rates["exec"].append(execute())
        rates["ref"].append(execute(numpy=True))
    fast, sim_rate, ref = max(rates["exec"]), max(rates["sim"]), max(rates["ref"])
    first = demo.steps / demo.wall_s  # the process's first simulate of the task, as a command runs it
    rows.append(
        Row("execute building, with /lfd logging", fast, "ticks/s", "simulate, same task", first, 1000.0)
    )
    rows.append(
        Row("execute building, with /lfd logging", fast, "ticks/s", "simulate, same task, rerun", sim_rate)
    )
    rows.append(Row("execute building, with /lfd logging", fast, "ticks/s", "numpy kernels", ref))


def bench_demo(rows: list[Row], folder: Path) -> None:
    import subprocess

    root = Path(__file__).resolve().parents[1]
    if not (root / "Makefile").exists():
        return
    t0 = time.perf_counter()
    subprocess.run(
        ["make", "-s", "demo", f"VENV={sys.prefix}", f"DEMO={folder / 'demo'}"],
        cwd=root,
        check=True,
        capture_output=True,
    )
    rows.append(Row("make demo pipeline, environment ready (s)", time.perf_counter() - t0, "s", "-", 0.0))


BENCHES: dict[str, Callable[[list[Row], Path], None]] = {
    "raycast": lambda rows, _f: bench_raycast(rows),
    "simulate": lambda rows, _f: bench_simulate(rows),
    "encoding": lambda rows, _f: bench_encoding(rows),
    "behaviors": bench_behaviors,
    "segment": bench_segment,
    "pf": bench_pf,
    "likelihood": bench_likelihood,
    "estimate": bench_estimate,  # quick: the K=30 reference is left out
    "execute": bench_execute,
    "demo": bench_demo,
}


def run(quick: bool, folder: Path, only: list[str] | None = None) -> list[dict[str, object]]:
    """Run the pipeline suites (all, or ``only`` those named) and return their rows."""
    rows: list[Row] = []
    for name, fn in BENCHES.items():
        if only is None or name in only:
            if name == "estimate":
                bench_estimate(rows, folder, quick)
            else:
                fn(rows, folder)
    return [asdict(r) | {"ratio": r.ratio} for r in rows]
