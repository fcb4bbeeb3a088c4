"""Success rates, not single runs: one fusion table driven from many starts (``execute --starts``).

The starts are perturbations of one pose (±0.5 m in x and y, ±20° in heading, drawn from the
seed; a draw whose robot disc touches a wall is drawn again) or poses read from a file. Every
start is one job: a pure function of the table's path, the world's name or path, the pose and
a seed, so a run on a Dask cluster gives the same numbers as one in this process. The rate is
completed / N with a Wilson 95 % interval.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.errors import ConfigError, LfdError
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.files import parse_yaml, read_text
from lfdfuse.network.table import load_table
from lfdfuse.parallel import Batch, Executor, Outcome
from lfdfuse.robot.pose import Pose
from lfdfuse.sim.robot import RobotParams
from lfdfuse.world.model import World, check_pose_free, load_world

#: the perturbation of ``--starts N``: up to this far from the base start in x and in y (m) …
SPREAD_M = 0.5
#: … and in heading (rad)
SPREAD_RAD = math.radians(20.0)
#: the most starts one command runs
MAX_STARTS = 10_000
#: draws per start before a base pose is declared too cramped to perturb
_DRAWS = 200


def wilson_interval(k: int, n: int, *, z: float = 1.959964) -> tuple[float, float]:
    """The Wilson score interval of a proportion ``k / n`` (95 % by default); (0, 1) when n = 0."""
    if n <= 0:
        return (0.0, 1.0)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def perturbed_starts(
    world: World, base: Pose, *, n: int, rng: np.random.Generator, radius_m: float = RobotParams().radius_m
) -> tuple[Pose, ...]:
    """``n`` poses within ±0.5 m, ±20° of ``base``, each clear of walls (rejection sampling)."""
    if not 1 <= n <= MAX_STARTS:
        raise ConfigError(f"--starts must be from 1 to {MAX_STARTS} starts, got {n}")
    check_pose_free(world, base.as_tuple(), what="start pose", radius=radius_m)
    poses = []
    for _ in range(n):
        for _ in range(_DRAWS):
            dx, dy = (float(v) for v in rng.uniform(-SPREAD_M, SPREAD_M, 2))
            dth = float(rng.uniform(-SPREAD_RAD, SPREAD_RAD))
            th = math.atan2(math.sin(base.theta + dth), math.cos(base.theta + dth))
            pose = Pose(round(base.x + dx, 4), round(base.y + dy, 4), round(th, 4))
            try:
                check_pose_free(world, pose.as_tuple(), what="start", radius=radius_m)
            except LfdError:
                continue
            poses.append(pose)
            break
        else:
            raise ConfigError(
                f"no free pose within {SPREAD_M:g} m of the start ({base.x:g}, {base.y:g}): start farther from walls"
            )
    return tuple(poses)


def read_starts(path: str | Path) -> tuple[Pose, ...]:
    """Poses from a YAML file: a list of ``[x, y, theta]`` or ``"x,y,theta"`` (m, m, rad)."""
    data = parse_yaml(read_text(path, what="starts file"), origin=str(path))
    if not isinstance(data, list) or not data:
        raise ConfigError(f"{path}: a starts file is a non-empty list of poses [x, y, theta]")
    if len(data) > MAX_STARTS:
        raise ConfigError(f"{path}: {len(data)} starts, at most {MAX_STARTS}")
    poses = []
    for k, item in enumerate(data):
        where = f"{path}: start {k + 1}"
        if isinstance(item, str):
            try:
                poses.append(Pose.parse(item))
            except LfdError as exc:
                raise ConfigError(f"{where}: {exc}") from None
            continue
        if not (isinstance(item, list) and len(item) == 3):
            raise ConfigError(f"{where} must be [x, y, theta], got {item!r}")
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in item):
            raise ConfigError(f"{where} must hold three numbers, got {item!r}")
        try:
            values = [float(v) for v in item]
        except OverflowError:
            raise ConfigError(f"{where}: a number too large") from None
        if not all(math.isfinite(v) for v in values):
            raise ConfigError(f"{where} must be finite, got {item!r}")
        poses.append(Pose(*values))
    return tuple(poses)


@dataclass(frozen=True)
class StartJob:
    """One run: what a worker needs to load and drive it (paths and numbers only)."""

    table: str  # absolute path of the fusion table
    world: str  # a built-in world name, or an absolute path
    start: tuple[float, float, float]
    max_time_s: float
    seed: int
    sensor_noise_m: float = 0.0
    stop_on_collision: bool = False


def run_start(job: StartJob) -> dict[str, Any]:
    """Drive the table from one start (the log goes to a temporary file) and return its report."""
    table = load_table(job.table)
    world = load_world(job.world)
    opts = ExecuteOptions(
        world=world,
        table=table,
        table_name=Path(job.table).name,
        start=Pose(*job.start),
        max_time_s=job.max_time_s,
        seed=job.seed,
        sensor_noise_m=job.sensor_noise_m,
        stop_on_collision=job.stop_on_collision,
    )
    with tempfile.TemporaryDirectory(prefix="lfdfuse-start-") as tmp:
        res = run_table(opts, out=Path(tmp) / "run.mcap", command="execute")
    return res.report


@dataclass(frozen=True)
class StartsResult:
    """Every start's report (or error) in start order, and the success rate over those that ran."""

    runs: tuple[
        dict[str, Any], ...
    ]  # {"start", "seed", <the single-run report>} or {"start", "seed", "error"}
    completed: int | None  # None: the table has no goals, nothing to complete
    ran: int
    failed: int

    @property
    def rate(self) -> float | None:
        return None if self.completed is None or self.ran == 0 else self.completed / self.ran

    @property
    def ci95(self) -> tuple[float, float] | None:
        return None if self.completed is None else wilson_interval(self.completed, self.ran)

    def to_dict(self) -> dict[str, Any]:
        ok = [r for r in self.runs if "error" not in r]
        ci = self.ci95
        return {
            "starts": list(self.runs),
            "runs": self.ran,
            "failed": self.failed,
            "completed": self.completed,
            "rate": None if self.rate is None else round(self.rate, 4),
            "ci95": None if ci is None else [round(ci[0], 4), round(ci[1], 4)],
            "collisions": sum(int(r["collisions"]) for r in ok),
            "runs_with_collisions": sum(int(r["collisions"]) > 0 for r in ok),
        }


def summarise_starts(
    jobs: tuple[StartJob, ...], outcomes: tuple[Outcome[dict[str, Any]], ...]
) -> StartsResult:
    runs: list[dict[str, Any]] = []
    for job, out in zip(jobs, outcomes, strict=True):
        head: dict[str, Any] = {"start": list(job.start), "seed": job.seed}
        runs.append({**head, **out.value} if out.value is not None else {**head, "error": out.error})
    ok = [r for r in runs if "error" not in r]
    has_goals = any(r["completed"] is not None for r in ok)
    completed = sum(bool(r["completed"]) for r in ok) if has_goals else None
    return StartsResult(tuple(runs), completed, len(ok), len(runs) - len(ok))


@dataclass(frozen=True)
class StartsOptions:
    table: Path
    world: str  # a built-in name or a path
    starts: int | Path  # how many perturbed starts, or a file of poses
    base: Pose | None = None  # the pose to perturb (default: the world's start)
    max_time_s: float = 300.0
    seed: int = 0
    sensor_noise_m: float = 0.0
    stop_on_collision: bool = False


def _spec(world: str) -> str:
    p = Path(world)
    return str(p.resolve()) if p.exists() else world


def plan_starts(opts: StartsOptions) -> tuple[StartJob, ...]:
    """The jobs of ``opts``: run k from pose k with sensor seed ``seed + k``."""
    load_table(opts.table)  # a bad table is one error before any job starts
    world = load_world(opts.world)
    if isinstance(opts.starts, int):
        base = opts.base or Pose(*world.start)
        poses = perturbed_starts(world, base, n=opts.starts, rng=np.random.default_rng(opts.seed))
    else:
        poses = read_starts(opts.starts)
        for k, p in enumerate(poses):
            check_pose_free(world, p.as_tuple(), what=f"start {k + 1}")
    table, spec = str(opts.table.resolve()), _spec(opts.world)
    return tuple(
        StartJob(
            table=table,
            world=spec,
            start=p.as_tuple(),
            max_time_s=opts.max_time_s,
            seed=opts.seed + k,
            sensor_noise_m=opts.sensor_noise_m,
            stop_on_collision=opts.stop_on_collision,
        )
        for k, p in enumerate(poses)
    )


def run_starts(opts: StartsOptions, *, executor: Executor) -> Batch[StartJob, dict[str, Any], StartsResult]:
    """A batch of every start on ``executor``: iterate it for progress, then ``.result()``."""
    jobs = plan_starts(opts)
    labels = [f"start {k + 1} ({j.start[0]:g}, {j.start[1]:g}, {j.start[2]:g})" for k, j in enumerate(jobs)]
    return Batch(
        run_start, jobs, executor=executor, reduce=lambda outs: summarise_starts(jobs, outs), labels=labels
    )
