"""Scripted teachers (DESIGN §9): find the way over the map and hold a lateral style.

A style teacher is deliberately *not* built from the behaviour primitives: it plans over the
free-space grid (:mod:`lfdfuse.sources.planner`), follows the path's tangent, and corrects its heading
from the side laser beams to keep its style (left, centre, right, slalom) or swerves around
obstacles on a chosen side. Imperfection is human-like and seeded: correlated heading noise and
a reaction delay of a few control periods.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.control.command import DriveParams, heading_to_command
from lfdfuse.control.safety import SafetyParams, free_heading
from lfdfuse.files import YamlKind, kind_of, read_yaml
from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Observation, Reading, ScanGeometry
from lfdfuse.sim.robot import wrap_angle
from lfdfuse.sim.sensors import CameraParams, target_reached
from lfdfuse.sources.planner import Planner
from lfdfuse.sources.tasks import Leg, parse_style, parse_task
from lfdfuse.world.parse import World


@dataclass(frozen=True)
class TeacherParams:
    """How the scripted teacher drives."""

    wall_distance_m: float = 0.6  # keep-left/right: distance of the robot centre to its wall
    side_sight_m: float = 2.0  # a side wall farther than this is ignored (door, junction)
    lateral_gain: float = 1.2  # rad of heading correction per metre of lateral error
    max_correction_rad: float = math.radians(35.0)
    slalom_amplitude_m: float = 0.45
    slalom_period_m: float = 6.0
    pass_clearance_m: float = 0.45  # gap between robot disc and obstacle when passing
    approach_m: float = 2.5  # steer straight at a visible target closer than this
    waypoint_reach_m: float = 1.0
    heading_noise_rad: float = math.radians(5.0)  # std of the correlated heading noise
    noise_correlation: float = 0.8  # AR(1) coefficient per control period
    delay_steps: int = 1  # reaction delay in control periods
    side_sector_rad: float = math.radians(50.0)  # half width of the side sectors
    lookahead_cells: int = 9  # the route's tangent is taken this many planner cells ahead (more: corners cut)


def side_range(
    ranges: np.ndarray, geom: ScanGeometry, angle_rad: float, half_width_rad: float = math.radians(8)
) -> float:
    """Smallest laser range within ``±half_width`` of a robot-frame angle (max range if none)."""
    a = geom.angles
    sel = np.abs(a - angle_rad) <= half_width_rad
    if not sel.any():
        return geom.max_range_m
    return float(ranges[sel].min())


# --- what ``--teacher`` names ----------------------------------------------------------------


@dataclass(frozen=True)
class ScriptedTeacher:
    """A style teacher over a chain of legs: a built-in style tours, a task reaches its targets."""

    legs: tuple[Leg, ...]
    #: how provenance and the summary name it: the style, or the task file's name
    name: str


@dataclass(frozen=True)
class NetworkTeacher:
    """A fusion table driving as the teacher (a known ground truth for round trips).

    Running a network is a later stage (``execute``); this names the table and carries its
    parsed YAML (for :func:`lfdfuse.network.table.parse_table`), read once.
    """

    path: Path
    data: Any
    name: str


TeacherSpec = ScriptedTeacher | NetworkTeacher


def _is_file(spec: str) -> bool:
    try:
        return Path(spec).exists()
    except OSError:  # a name too long for the file system: not a file, so a style name
        return False


def teacher_from(spec: str, world: World) -> TeacherSpec:
    """What a ``--teacher`` spec names: a built-in style (see ``STYLES``), a task YAML or a
    fusion table YAML (told apart by :func:`lfdfuse.files.kind_of`).

    A task's targets must be in ``world``; anything else wrong is one :class:`ConfigError`
    (or :class:`WorldError`) before a run starts.
    """
    if not (spec.endswith((".yaml", ".yml")) or _is_file(spec)):
        return ScriptedTeacher((Leg(None, parse_style(spec)),), spec)
    data = read_yaml(spec, what="teacher file")
    name = Path(spec).name
    if kind_of(data) is YamlKind.TABLE:
        return NetworkTeacher(Path(spec), data, name)
    legs = tuple(parse_task(data, origin=spec))  # a world or anything else: the task's own error
    for leg in legs:
        if leg.target is not None:
            world.target(leg.target)
    return ScriptedTeacher(legs, name)


#: a wall-follower that travelled less than STUCK_M in STUCK_TICKS ticks tours by the planner
#: for ESCAPE_TICKS ticks
STUCK_TICKS = 60
STUCK_M = 0.3
ESCAPE_TICKS = 150


class StyleTeacher:
    """Drives a chain of legs; a leg without target tours the map holding its style."""

    def __init__(
        self,
        *,
        world: World,
        legs: list[Leg],
        planner: Planner,
        geometry: ScanGeometry,
        camera: CameraParams,
        drive: DriveParams,
        rng: np.random.Generator,
        params: TeacherParams = TeacherParams(),
    ) -> None:
        for leg in legs:
            if leg.target is not None:
                world.target(leg.target)  # raises naming the missing target
        self.world, self.legs, self.planner = world, legs, planner
        self.geometry, self.camera, self.drive = geometry, camera, drive
        self._angles = geometry.angles  # computed once, read every tick
        #: per side (+1 left, −1 right), the beams the wall-follower reads the wall on
        self._side_beams = {
            side: (side * self._angles > math.radians(15)) & (side * self._angles <= math.pi / 2 + 1e-9)
            for side in (1.0, -1.0)
        }
        self.rng, self.p = rng, params
        self.safety = SafetyParams()
        self.leg_index = 0
        self.reached: list[tuple[str, int]] = []  # (target, step index)
        self._noise = 0.0
        self._turn_sign = 0.0
        self._queue: deque[float] = deque()
        self._travelled = 0.0
        self._last: Pose | None = None
        self._tour: list[tuple[float, float]] = []
        self._steps = 0
        # distance travelled at each of the last ticks, to notice a wall-follower that is stuck
        self._progress: deque[float] = deque(maxlen=STUCK_TICKS)
        self._escape_until = 0
        self._obstacles = [self._obstacle_disc(i) for i in range(len(world.obstacles))]

    @property
    def done(self) -> bool:
        return self.leg_index >= len(self.legs)

    def _obstacle_disc(self, i: int) -> tuple[float, float, float]:
        poly = self.world.obstacles[i].polygon()
        c = poly.centroid
        r = max(math.hypot(x - c.x, y - c.y) for x, y in poly.exterior.coords)
        return c.x, c.y, r

    def _tour_point(self, pose: Pose) -> tuple[float, float]:
        """Next tour waypoint: the targets in turn, or the farthest point and back."""
        if (
            self._tour
            and math.hypot(self._tour[0][0] - pose.x, self._tour[0][1] - pose.y) < self.p.waypoint_reach_m
        ):
            self._tour.pop(0)
        if not self._tour:
            if len(self.world.targets) >= 2:
                self._tour = [(t.x, t.y) for t in self.world.targets]
            else:
                far = self.planner.farthest(pose.x, pose.y)
                self._tour = [far, self.planner.farthest(*far)]
        return self._tour[0]

    def command(self, obs: Observation) -> tuple[float, float]:
        pose, reading = obs.pose, obs.reading
        """The command ``(v, ω)`` for this control period."""
        self._steps += 1
        if self._last is not None:
            self._travelled += math.hypot(pose.x - self._last.x, pose.y - self._last.y)
        self._last = pose
        self._progress.append(self._travelled)
        seen = {d.name: d for d in reading.detections}
        if not self.done:
            goal = self.legs[self.leg_index].target
            if goal is not None and goal in seen and target_reached(seen[goal].range_m, self.camera):
                self.reached.append((goal, self._steps - 1))
                self.leg_index += 1
        if self.done:
            return 0.0, 0.0
        leg = self.legs[self.leg_index]
        desired = self._desired_heading(pose, reading, leg, seen)
        # correlated heading noise and a reaction delay: a human's imperfection
        a = self.p.noise_correlation
        self._noise = a * self._noise + math.sqrt(1 - a * a) * float(
            self.rng.normal(0.0, self.p.heading_noise_rad)
        )
        rel_now = wrap_angle(desired + self._noise)
        if abs(rel_now) > math.radians(150) and self._turn_sign != 0.0:
            # turning around: commit to one direction instead of dithering at ±180°
            rel_now = math.copysign(abs(rel_now), self._turn_sign)
        self._turn_sign = math.copysign(1.0, rel_now) if abs(rel_now) > math.radians(60) else 0.0
        self._queue.append(rel_now)
        rel = self._queue.popleft() if len(self._queue) > self.p.delay_steps else self._queue[0]
        v, w = heading_to_command(np.array(rel), self.drive)
        return float(v), float(w)

    def _desired_heading(self, pose: Pose, reading: Reading, leg: Leg, seen: dict[str, Any]) -> float:
        """Robot-frame heading (rad) the teacher wants now."""
        if leg.target is not None:
            det = seen.get(leg.target)
            if det is not None and det.range_m < self.p.approach_m:
                return self._safe(float(det.bearing_rad), reading)
            t = self.world.target(leg.target)
            gx, gy = t.x, t.y
        elif leg.style in ("keep-left", "keep-right") and not self._escaping():
            # touring while keeping to one side: follow that wall, into every opening on it,
            # as a person told "keep left" would (a planner's route would also turn the other way)
            return self._safe(self._wall_follow(reading, 1.0 if leg.style == "keep-left" else -1.0), reading)
        else:
            gx, gy = self._tour_point(pose)
        fld = self.planner.field(gx, gy)
        near = self.planner.follow(pose.x, pose.y, fld, 2)
        far = self.planner.follow(pose.x, pose.y, fld, self.p.lookahead_cells)
        tx, ty = far[0] - near[0], far[1] - near[1]
        if tx == 0.0 and ty == 0.0:
            tx, ty = gx - pose.x, gy - pose.y
        path = math.atan2(ty, tx)
        rel_path = wrap_angle(path - pose.theta)
        aim = self._pass_obstacle(pose, path, leg.style)
        if aim is not None:
            return self._safe(wrap_angle(math.atan2(aim[1] - pose.y, aim[0] - pose.x) - pose.theta), reading)
        return self._safe(rel_path + self._lateral(reading, leg.style), reading)

    def _escaping(self) -> bool:
        """Whether a stuck wall-follower tours by the planner for a while instead.

        On real maps a side opening can be a gap narrower than the robot: the wall-follower turns
        into it and the reflex holds it there. A person would give up and drive on; so does the
        teacher, when it has moved less than ``STUCK_M`` in ``STUCK_TICKS`` ticks.
        """
        if self._steps < self._escape_until:
            return True
        full = len(self._progress) == STUCK_TICKS
        if full and self._progress[-1] - self._progress[0] < STUCK_M:
            self._escape_until = self._steps + ESCAPE_TICKS
            self._progress.clear()
            return True
        return False

    def _safe(self, rel: float, reading: Reading) -> float:
        """The free direction nearest ``rel``: a person does not drive into a wall."""
        return free_heading(rel, reading.ranges_m, self._angles, self.safety)

    def _wall_follow(self, reading: Reading, side: float) -> float:
        """Heading along the wall on ``side`` (+1 left, −1 right) at the style's distance."""
        p = self.p
        a = self._angles
        r = reading.ranges_m
        sel = self._side_beams[side]
        if not sel.any():
            return 0.0
        rs, as_ = r[sel], a[sel]
        k = int(np.argmin(rs))
        if rs[k] > p.side_sight_m:
            return side * math.radians(50)  # the wall ends: turn into the opening
        tangent = float(as_[k]) - side * math.pi / 2  # along the wall, forward
        err = float(rs[k]) - p.wall_distance_m  # > 0: too far, turn toward the wall
        # min/max: np.clip's value, without its cost on a scalar
        return tangent + side * min(max(p.lateral_gain * err, -p.max_correction_rad), p.max_correction_rad)

    def _lateral(self, reading: Reading, style: str) -> float:
        p = self.p
        # the nearest return in a wide side sector: corners are rounded at the style's distance
        left = side_range(reading.ranges_m, self.geometry, math.pi / 2, p.side_sector_rad)
        right = side_range(reading.ranges_m, self.geometry, -math.pi / 2, p.side_sector_rad)
        see_l, see_r = left < p.side_sight_m, right < p.side_sight_m
        err = 0.0  # positive: the robot should move to its left
        if style == "keep-left" and see_l:
            err = left - p.wall_distance_m
        elif style == "keep-right" and see_r:
            err = p.wall_distance_m - right
        elif style in ("keep-center", "pass-left", "pass-right") and see_l and see_r:
            err = (left - right) / 2
        elif style == "slalom" and see_l and see_r:
            want = p.slalom_amplitude_m * math.sin(2 * math.pi * self._travelled / p.slalom_period_m)
            err = want - (right - left) / 2
        return float(np.clip(p.lateral_gain * err, -p.max_correction_rad, p.max_correction_rad))

    def _pass_obstacle(self, pose: Pose, path: float, style: str) -> tuple[float, float] | None:
        """An aim point beside the next obstacle ahead, on the side the style asks for."""
        if style not in ("pass-left", "pass-right") or not self._obstacles:
            return None
        ux, uy = math.cos(path), math.sin(path)
        side = 1.0 if style == "pass-left" else -1.0
        best: tuple[float, float] | None = None
        best_s = math.inf
        for ox, oy, r in self._obstacles:
            dx, dy = ox - pose.x, oy - pose.y
            s = dx * ux + dy * uy
            lat = ux * dy - uy * dx
            if -0.2 < s < 3.5 and abs(lat) < r + 1.0 and s < best_s:
                off = r + 0.25 + self.p.pass_clearance_m
                # aim beside the obstacle, a little ahead of it so the robot straightens out
                best = (ox - side * uy * off + ux * 0.4, oy + side * ux * off + uy * 0.4)
                best_s = s
        return best
