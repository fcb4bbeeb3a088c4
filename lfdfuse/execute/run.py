"""``execute``: a fusion table drives the robot; also the network teacher of ``simulate``.

The :class:`NetworkDriver` senses through the same behaviour code as ``segment`` (one scan at a
time), asks the :class:`~lfdfuse.network.NetworkRuntime` for the fused vector and turns it into a
command with the one vector ↔ command mapping. It logs why the robot turns: behaviour outputs,
the BAC, the active step, the fused vector, and an overlay of one arrow per applicable
behaviour's weighted vector plus the fused one.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import orjson

from lfdfuse.behaviors.primitives import BehaviorParams, Observations, compute
from lfdfuse.control.drive import heading_to_command
from lfdfuse.control.safety import SafetyParams, free_heading
from lfdfuse.errors import ConfigError
from lfdfuse.files import write_text_atomic
from lfdfuse.log import LogWriter
from lfdfuse.log import messages as msg
from lfdfuse.network.runtime import Decision, NetworkRuntime, step_name_of
from lfdfuse.network.table import FusionTable
from lfdfuse.segment.pipeline import LFD_TOPICS
from lfdfuse.sim.robot import Pose, RobotParams
from lfdfuse.sim.sensors import Reading, SensorParams, Sensors, target_reached
from lfdfuse.sources.simulate import RunSummary, provenance, run_loop, side_beam_index
from lfdfuse.world.model import World

EXEC_TOPICS = {
    "/lfd/behaviors": LFD_TOPICS["/lfd/behaviors"],
    "/lfd/bac": LFD_TOPICS["/lfd/bac"],
    "/lfd/step": "lfdfuse.NetworkStep",
    "/lfd/fused": "lfdfuse.FusedVector",
    "/lfd/overlay": "foxglove.SceneUpdate",
}

_PALETTE = [
    (0.9, 0.3, 0.2),
    (0.2, 0.6, 0.9),
    (0.3, 0.8, 0.3),
    (0.9, 0.7, 0.1),
    (0.7, 0.3, 0.9),
    (0.1, 0.8, 0.8),
    (0.9, 0.4, 0.7),
    (0.6, 0.5, 0.3),
    (0.5, 0.5, 0.9),
    (0.8, 0.8, 0.5),
    (0.4, 0.7, 0.5),
    (0.9, 0.6, 0.4),
    (0.6, 0.6, 0.6),
]


def check_table_world(table: FusionTable, world: World) -> None:
    missing = [t for t in table.targets() if t not in world.target_names]
    if missing:
        raise ConfigError(
            f"the table needs target{'s' if len(missing) > 1 else ''} {', '.join(missing)} that world {world.name!r} lacks"
            f" (it has: {', '.join(world.target_names) or 'none'})"
        )


class NetworkDriver:
    """Drives with a fusion table; optional heading noise makes it a network *teacher*."""

    def __init__(
        self,
        *,
        table: FusionTable,
        world: World,
        sensors: SensorParams,
        rng: np.random.Generator,
        heading_noise_rad: float = 0.0,
        robot: RobotParams = RobotParams(),
        safety: SafetyParams | None = SafetyParams(),
    ) -> None:
        check_table_world(table, world)
        self.table = table
        self.runtime = NetworkRuntime(table)
        self.sensors = sensors
        self.params = BehaviorParams(reach_m=sensors.camera.reach_m)
        self.rng = rng
        self.noise = heading_noise_rad
        self.robot = robot
        self.targets = world.target_names
        self.geometry = sensors.laser.geometry
        self.sonar_angles = sensors.sonar.geometry.angles
        self.reached: list[tuple[str, int]] = []
        self.ticks = 0
        self.unseen_ticks = 0
        self.last: Decision | None = None
        self._turn = 0.0
        self.safety = safety
        self.reflex_ticks = 0
        self.last_outputs: Any = None
        self.side: dict[str, list[tuple[float, float]]] = defaultdict(list)
        self._il = side_beam_index(self.geometry.angles, math.pi / 2)
        self._ir = side_beam_index(self.geometry.angles, -math.pi / 2)

    @property
    def done(self) -> bool:
        return self.runtime.complete

    def command(self, pose: Pose, reading: Reading) -> tuple[float, float]:
        obs = Observations.from_detections(
            ranges_m=reading.ranges_m[None, :],
            geometry=self.geometry,
            detections=[reading.detections],
            target_names=self.targets,
            sonar_m=reading.sonar_m[None, :],
            sonar_angles_rad=self.sonar_angles,
            sonar_max_m=self.sensors.sonar.max_range_m,
        )
        outputs = compute(obs, self.table.behaviors, self.params)
        reached = {d.name for d in reading.detections if target_reached(d.range_m, self.sensors.camera)}
        dec = self.runtime.decide(outputs, reached)
        for goal in dec.achieved_now:
            self.reached.append((goal, self.ticks))
        self.last, self.last_outputs = dec, outputs
        self.ticks += 1
        if dec.step is None:
            return 0.0, 0.0
        self.unseen_ticks += dec.unseen
        self.side[step_name_of(dec.path, self.table)].append(
            (float(reading.ranges_m[self._il]), float(reading.ranges_m[self._ir]))
        )
        fx, fy = float(dec.fused[0]), float(dec.fused[1])
        heading = math.atan2(fy, fx) if (fx, fy) != (0.0, 0.0) else 0.0  # no pull at all: straight on
        if abs(heading) > math.radians(120) and self._turn != 0.0:
            # the pull is behind the robot: commit to one turning direction while turning round,
            # instead of dithering as the behind-vector swings from side to side
            heading = math.copysign(abs(heading), self._turn)
        self._turn = math.copysign(1.0, heading) if abs(heading) > math.radians(90) else 0.0
        if self.noise > 0:
            heading += float(self.rng.normal(0.0, self.noise))
        if self.safety is not None:
            safe = free_heading(heading, reading.ranges_m, self.geometry.angles, self.safety)
            self.reflex_ticks += safe != heading
            heading = safe
        v, w = heading_to_command(np.array(heading), self.robot.drive)
        return float(v), float(w)

    def log_step(self, log: LogWriter, t_ns: int) -> None:
        dec, out = self.last, self.last_outputs
        if dec is None or out is None:
            return
        ts = msg.stamp(t_ns)
        names = self.table.behaviors
        vec = np.round(out.vectors[0], 6)
        app = out.applicable[0]
        log.write_raw(
            "/lfd/behaviors",
            t_ns,
            orjson.dumps(
                {
                    "timestamp": ts,
                    "behaviors": [
                        {
                            "name": n,
                            "x": float(vec[j, 0]),
                            "y": float(vec[j, 1]),
                            "applicable": bool(app[j]),
                            "goal_met": bool(out.goal_met[0, j]),
                        }
                        for j, n in enumerate(names)
                    ],
                }
            ),
        )
        log.write_raw(
            "/lfd/bac",
            t_ns,
            orjson.dumps(
                {"timestamp": ts, "bac": dec.bac, "applicable": [n for j, n in enumerate(names) if app[j]]}
            ),
        )
        step = step_name_of(dec.path, self.table) if dec.step is not None else None
        log.write_raw(
            "/lfd/step",
            t_ns,
            orjson.dumps(
                {
                    "timestamp": ts,
                    "step": step,
                    "goal": dec.step.goal if dec.step is not None else None,
                    "bac": dec.bac,
                    "default_weights": dec.unseen,
                    "achieved": [g for g, _ in self.reached],
                }
            ),
        )
        log.write_raw(
            "/lfd/fused",
            t_ns,
            orjson.dumps(
                {
                    "timestamp": ts,
                    "x": float(dec.fused[0]),
                    "y": float(dec.fused[1]),
                    "weights": {k: round(v, 4) for k, v in dec.weights.items()},
                }
            ),
        )
        arrows = [
            msg.Arrow(
                dec.weights[n] * float(vec[j, 0]),
                dec.weights[n] * float(vec[j, 1]),
                _PALETTE[j % len(_PALETTE)],
                1.5,
            )
            for j, n in enumerate(names)
            if app[j] and n in dec.weights
        ]
        arrows.append(msg.Arrow(float(dec.fused[0]), float(dec.fused[1]), (1.0, 1.0, 1.0), 1.5))
        log.write("/lfd/overlay", t_ns, msg.arrow_scene(t_ns, "fusion", arrows))


@dataclass(frozen=True)
class ExecuteOptions:
    world: World
    table: FusionTable
    table_name: str = "fusion.yaml"
    start: Pose | None = None
    max_time_s: float = 300.0
    seed: int = 0
    heading_noise_rad: float = 0.0
    sensor_noise_m: float = 0.0
    stop_on_collision: bool = False
    robot: RobotParams = field(default_factory=RobotParams)


@dataclass(frozen=True)
class ExecuteResult:
    summary: RunSummary
    report: dict[str, Any]


def _goal_list(table: FusionTable) -> list[tuple[str, str]]:
    out: list[tuple[str, str]] = []

    def walk(net: Any) -> None:
        for s in net.steps:
            if s.network is not None:
                walk(s.network)
            elif s.goal is not None:
                out.append((s.name, s.goal))

    walk(table.network)
    return out


def drive_table(
    opts: ExecuteOptions, *, out: str | Path, command: str, teacher: bool = False, progress: Any = None
) -> ExecuteResult:
    """Run a fusion table in a world, log the run to ``out`` and build the report."""
    if opts.max_time_s <= 0:
        raise ConfigError("--max-time must be positive")
    rng = np.random.default_rng(opts.seed)
    params = SensorParams().with_noise(opts.sensor_noise_m) if opts.sensor_noise_m > 0 else SensorParams()
    sensors = Sensors(opts.world, params)
    driver = NetworkDriver(
        table=opts.table,
        world=opts.world,
        sensors=params,
        rng=rng,
        heading_noise_rad=opts.heading_noise_rad,
        robot=opts.robot,
    )
    start = opts.start or Pose(*opts.world.start)
    meta = provenance(
        command=command,
        seed=opts.seed,
        world=opts.world,
        sensors=params,
        teacher=opts.table_name if teacher else "",
        table=opts.table_name,
        behaviors=",".join(opts.table.behaviors),
        duration_s=repr(opts.max_time_s),
        start=",".join(repr(v) for v in start.as_tuple()),
        heading_noise_rad=repr(opts.heading_noise_rad),
    )
    summary = run_loop(
        world=opts.world,
        driver=driver,
        start=start,
        duration_s=opts.max_time_s,
        out=out,
        metadata=meta,
        rng=rng,
        sensors=sensors,
        robot=opts.robot,
        reached=lambda: driver.reached,
        step_logger=None if teacher else driver,
        extra_topics=None if teacher else EXEC_TOPICS,
        stop_on_collision=opts.stop_on_collision,
        progress=progress,
    )
    reached_at = list(summary.reached)
    goals = []
    for name, target in _goal_list(opts.table):
        hit = next((i for i, (g, _) in enumerate(reached_at) if g == target), None)
        t = None
        if hit is not None:
            t = reached_at.pop(hit)[1]
        goals.append(
            {
                "name": name,
                "target": target,
                "reached": t is not None,
                "time_s": None if t is None else round(t, 2),
            }
        )
    steps = []
    for name, pairs in driver.side.items():
        arr = np.array(pairs)
        steps.append(
            {
                "name": name,
                "left_range_mean_m": round(float(arr[:, 0].mean()), 3),
                "right_range_mean_m": round(float(arr[:, 1].mean()), 3),
                "ticks": len(pairs),
                "style": corridor_style(arr[:, 0], arr[:, 1]),
            }
        )
    active_ticks = sum(len(p) for p in driver.side.values())
    report = {
        "completed": bool(summary.completed),
        "duration_s": round(summary.duration_s, 2),
        "collisions": summary.collisions,
        "path_length_m": round(summary.distance_m, 2),
        "goals": goals,
        "steps": steps,
        "left_range_mean_m": round(summary.left_range_mean_m, 3),
        "right_range_mean_m": round(summary.right_range_mean_m, 3),
        "unseen_bac_fraction": round(driver.unseen_ticks / max(active_ticks, 1), 4),
        "reflex_fraction": round(driver.reflex_ticks / max(active_ticks, 1), 4),
    }
    return ExecuteResult(summary, report)


def write_report(report: dict[str, Any], path: str | Path) -> None:
    write_text_atomic(path, json.dumps(report, indent=1) + "\n")


def corridor_style(left_m: np.ndarray, right_m: np.ndarray, *, sight_m: float = 2.0) -> str:
    """The paper's style measure (Fig. 10) in words, from the ±90° ranges of each tick.

    Only ticks with both walls in sight count (corridor stretches): a mean over openings, doors and
    crossings says more about the building than about the robot. ``left``, ``right`` or
    ``centre`` (median offset under 0.25 m); ``unknown`` without such ticks.
    """
    both = (left_m < sight_m) & (right_m < sight_m)
    if not both.any():
        return "unknown"
    offset = float(np.median(right_m[both] - left_m[both])) / 2  # > 0: the robot is left of centre
    if offset > 0.25:
        return "left"
    if offset < -0.25:
        return "right"
    return "centre"


def verdict(report: dict[str, Any]) -> str:
    """One line: task completed (when it has goals) and the style of each step."""
    parts = []
    if report["goals"]:
        done = sum(g["reached"] for g in report["goals"])
        parts.append(
            f"task {'completed' if report['completed'] else 'NOT completed'} ({done}/{len(report['goals'])} goals)"
        )
    styles = [f"{s['name']} keeps {s.get('style', 'unknown')}" for s in report["steps"]]
    parts.append("; ".join(styles) if styles else "no step ran")
    parts.append(f"{report['collisions']} collisions")
    return ", ".join(parts)
