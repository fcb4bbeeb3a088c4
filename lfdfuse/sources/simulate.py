"""The closed loop shared by ``simulate`` and ``execute``: sense, log, decide, move.

A :class:`Driver` (a scripted teacher, or a behaviour network) turns each reading into a
command. The loop writes the raw channels of DESIGN §5 at every control period and leaves
room for a driver to log its own channels.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from lfdfuse import __version__
from lfdfuse.errors import ConfigError
from lfdfuse.log import LogWriter
from lfdfuse.log import messages as msg
from lfdfuse.sim.robot import Pose, RobotParams, move
from lfdfuse.sim.sensors import Reading, SensorParams, Sensors
from lfdfuse.sources.planner import Planner
from lfdfuse.sources.teachers import Leg, StyleTeacher, TeacherParams
from lfdfuse.world.model import World, check_pose_free

Progress = Callable[[float, float], None]  # (done, total) in seconds of simulated time


class Driver(Protocol):
    """Decides a command from what the robot senses."""

    @property
    def done(self) -> bool: ...

    def command(self, pose: Pose, reading: Reading) -> tuple[float, float]: ...


class StepLogger(Protocol):
    """Optional per-step logging of a driver's own channels."""

    def log_step(self, log: LogWriter, t_ns: int) -> None: ...


@dataclass(frozen=True)
class RunSummary:
    """What happened in a closed-loop run."""

    steps: int
    duration_s: float
    distance_m: float
    collisions: int
    reached: tuple[tuple[str, float], ...]  # (target, time_s) in order
    completed: bool
    out: str
    left_range_mean_m: float
    right_range_mean_m: float
    poses: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, 3)))
    left_m: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    right_m: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))


def side_beam_index(angles: np.ndarray, angle_rad: float) -> int:
    return int(np.argmin(np.abs(angles - angle_rad)))


def provenance(
    *, command: str, seed: int, world: World, sensors: SensorParams, **extra: str
) -> dict[str, str]:
    meta = {
        "tool": "lfdfuse",
        "version": __version__,
        "command": command,
        "seed": str(seed),
        "world": world.name,
        "laser_max_range_m": repr(sensors.laser.max_range_m),
        "sonar_max_range_m": repr(sensors.sonar.max_range_m),
        "camera_reach_m": repr(sensors.camera.reach_m),
        "dt_s": "0.1",
    }
    meta.update(extra)
    return meta


def run_loop(
    *,
    world: World,
    driver: Driver,
    start: Pose,
    duration_s: float,
    out: str | Path,
    metadata: dict[str, str],
    rng: np.random.Generator,
    sensors: Sensors,
    robot: RobotParams,
    reached: Callable[[], list[tuple[str, int]]],
    step_logger: StepLogger | None = None,
    extra_topics: dict[str, str] | None = None,
    stop_on_collision: bool = False,
    progress: Progress | None = None,
) -> RunSummary:
    """Drive ``driver`` from ``start`` for at most ``duration_s`` and log everything to ``out``."""
    check_pose_free(world, start.as_tuple(), what="start pose", radius=robot.radius_m)
    dt_ns = int(round(robot.dt_s * 1e9))
    n_max = int(math.floor(duration_s / robot.dt_s + 1e-9))
    geom = sensors.params.laser.geometry
    i_left = side_beam_index(geom.angles, math.pi / 2)
    i_right = side_beam_index(geom.angles, -math.pi / 2)
    sonar_scan = sensors.params.sonar.geometry
    pose = start
    poses = np.zeros((n_max + 1, 3))
    left = np.zeros(n_max + 1)
    right = np.zeros(n_max + 1)
    collisions, blocked_before, distance = 0, False, 0.0
    steps = 0
    with LogWriter(out, metadata=metadata) as log:
        for topic, schema in (extra_topics or {}).items():
            log.add_topic(topic, schema)
        log.attach("world.yaml", "application/yaml", world.source.encode())
        log.write("/world", 0, msg.world_scene(0, world))
        for k in range(n_max + 1):
            t_ns = k * dt_ns
            reading = sensors.sense(pose, rng)
            poses[k] = (pose.x, pose.y, pose.theta)
            left[k], right[k] = reading.ranges_m[i_left], reading.ranges_m[i_right]
            log.write("/scan", t_ns, msg.laser_scan(t_ns, reading.ranges_m, geom))
            log.write("/sonar", t_ns, msg.laser_scan(t_ns, reading.sonar_m, sonar_scan))
            log.write("/pose", t_ns, msg.pose_in_frame(t_ns, pose.x, pose.y, pose.theta))
            log.write("/tf", t_ns, msg.frame_transform(t_ns, pose.x, pose.y, pose.theta))
            log.write("/targets", t_ns, msg.target_detections(t_ns, reading.detections))
            v, w = driver.command(pose, reading)
            log.write("/cmd_vel", t_ns, msg.twist(t_ns, v, w))
            if step_logger is not None:
                step_logger.log_step(log, t_ns)
            steps = k + 1
            if progress is not None and k % 50 == 0:
                progress(k * robot.dt_s, duration_s)
            if driver.done or k == n_max:
                break
            new, blocked = move(pose, v, w, params=robot, caster=sensors.caster)
            if blocked and not blocked_before:
                collisions += 1
            blocked_before = blocked
            distance += math.hypot(new.x - pose.x, new.y - pose.y)
            pose = new
            if blocked and stop_on_collision:
                break
    if progress is not None:
        progress(duration_s, duration_s)
    hits = tuple((name, k * robot.dt_s) for name, k in reached())
    return RunSummary(
        steps=steps,
        duration_s=(steps - 1) * robot.dt_s,
        distance_m=distance,
        collisions=collisions,
        reached=hits,
        completed=driver.done,
        out=str(out),
        left_range_mean_m=float(left[:steps].mean()),
        right_range_mean_m=float(right[:steps].mean()),
        poses=poses[:steps],
        left_m=left[:steps],
        right_m=right[:steps],
    )


@dataclass(frozen=True)
class SimulateOptions:
    world: World
    legs: list[Leg]
    teacher_name: str
    duration_s: float = 120.0
    seed: int = 0
    start: Pose | None = None
    sensor_noise_m: float = 0.0
    teacher: TeacherParams = field(default_factory=TeacherParams)
    robot: RobotParams = field(default_factory=RobotParams)


def simulate(opts: SimulateOptions, *, out: str | Path, progress: Progress | None = None) -> RunSummary:
    """Run a scripted teacher in a world and record the demonstration to ``out``."""
    if opts.duration_s <= 0:
        raise ConfigError("duration must be positive")
    rng = np.random.default_rng(opts.seed)
    params = SensorParams().with_noise(opts.sensor_noise_m) if opts.sensor_noise_m > 0 else SensorParams()
    sensors = Sensors(opts.world, params)
    start = opts.start or Pose(*opts.world.start)
    check_pose_free(opts.world, start.as_tuple(), what="start pose", radius=opts.robot.radius_m)
    planner = Planner(opts.world, robot_radius_m=opts.robot.radius_m)
    teacher = StyleTeacher(
        world=opts.world,
        legs=opts.legs,
        planner=planner,
        geometry=params.laser.geometry,
        camera=params.camera,
        drive=opts.robot.drive,
        rng=rng,
        params=opts.teacher,
    )
    meta = provenance(
        command="simulate",
        seed=opts.seed,
        world=opts.world,
        sensors=params,
        teacher=opts.teacher_name,
        duration_s=repr(opts.duration_s),
        start=",".join(repr(v) for v in start.as_tuple()),
        task=";".join(f"{leg.target or '-'}:{leg.style}" for leg in opts.legs),
    )
    return run_loop(
        world=opts.world,
        driver=teacher,
        start=start,
        duration_s=opts.duration_s,
        out=out,
        metadata=meta,
        rng=rng,
        sensors=sensors,
        robot=opts.robot,
        reached=lambda: teacher.reached,
        progress=progress,
    )
