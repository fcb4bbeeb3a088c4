"""A behaviour network stepped tick by tick: the learned controller, or a network *teacher*.

:class:`NetworkStepper` takes one observation per tick and answers one command. It senses
through the same behaviour code as ``segment`` (one scan at a time, carrying the stateful
primitives' state and the opening sensors from tick to tick, as ``segment`` carries them from
scan to scan), asks the :class:`~lfdfuse.network.runtime.NetworkRuntime` for the fused vector
and turns it into a command with the one vector ↔ command mapping, below a safety reflex. It
keeps what it decided (``last``) so a recorder can log why the robot turned, and asks for help
(:class:`HelpRequest`) when it enters a BAC its table cannot drive with confidence. ``execute``,
``simulate``'s network teacher, ``teleop --table`` and ``drive`` all step the network through it.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from lfdfuse.behaviors import kernels
from lfdfuse.behaviors.catalogue import spec_of
from lfdfuse.behaviors.openings import OpeningSensor, ahead_bearings, ahead_range
from lfdfuse.behaviors.primitives import BehaviorParams, BehaviorState, Observations, compute
from lfdfuse.behaviors.spec import attract_target, made_observations, unseen
from lfdfuse.control.command import heading_command
from lfdfuse.control.safety import SafetyParams, free_heading
from lfdfuse.errors import ConfigError
from lfdfuse.log.lfd import HelpReason
from lfdfuse.network.landmark_goals import Cues
from lfdfuse.network.runtime import Decision, NetworkRuntime, step_name_of
from lfdfuse.network.table import FusionTable, Network, leaf_steps
from lfdfuse.robot.readings import Observation, ScanGeometry
from lfdfuse.sim.loop import side_beam_index
from lfdfuse.sim.robot import RobotParams
from lfdfuse.sim.sensors import SensorParams, target_reached
from lfdfuse.world.parse import World

__all__ = ["HelpReason", "HelpRequest", "NetworkStepper", "help_reason", "weighted_targets"]


@dataclass(frozen=True)
class HelpRequest:
    """The network asks for help: at ``t_ns`` its active ``step`` met ``bac``, which the table has
    no row for (``unseen BAC``: default weights drive) or whose row the demonstration could not pin
    down (``not identifiable``: the prior decides)."""

    t_ns: int
    step: str
    bac: int
    why: HelpReason

    @property
    def t_s(self) -> float:
        return self.t_ns / 1e9


def help_reason(decision: Decision) -> HelpReason | None:
    """Why this decision needs help, or None when its row is a learned, identifiable one."""
    if decision.step is None:
        return None
    if decision.unseen:
        return "unseen BAC"
    row = decision.step.row(decision.bac)
    if row is not None and row.identifiable is False:
        return "not identifiable"
    return None


def weighted_targets(table: FusionTable) -> list[str]:
    """Targets the table cannot run without: those of attract behaviours that carry weight.

    An ``attract_<t>`` with zero weight everywhere never moves the robot; without its target it is
    simply never applicable (DESIGN §8: only behaviours that carry weight need their targets). A
    goal whose target the world lacks is never achieved: its step drives on with its weights (a
    tour learned past targets still keeps its style in a building without them), and the report
    lists the goal as not reached.
    """
    weights: list[dict[str, float]] = [table.default_weights]

    def walk(net: Network) -> None:
        for step in net.steps:
            if step.network is not None:
                walk(step.network)
            if step.default_weights:
                weights.append(step.default_weights)
            weights.extend(row.weights for row in step.fusion)

    walk(table.network)
    carried = {b for w in weights for b, v in w.items() if v > 0}
    return [t for b in table.behaviors if (t := attract_target(b)) is not None and b in carried]


def check_table_world(table: FusionTable, world: World) -> None:
    missing = [t for t in weighted_targets(table) if t not in world.target_names]
    if missing:
        raise ConfigError(
            f"the table needs target{'s' if len(missing) > 1 else ''} {', '.join(missing)} that world {world.name!r} lacks"
            f" (it has: {', '.join(world.target_names) or 'none'})"
        )


def landmark_lags(table: FusionTable) -> list[float]:
    """The lags other than the sensor's default that the table's landmarks are sensed with."""
    return sorted(
        {s.landmark.lag_m for s in leaf_steps(table) if s.landmark is not None and s.landmark.lag_m}
    )


#: the cues of a tick where nothing is sensed (a table without landmarks)
_NO_CUES = Cues()

#: a heading this far to a side turns the robot (nearly) on the spot: the speed falls with cos θ
_ON_THE_SPOT_RAD = math.radians(85.0)
#: a pull further round than this is behind the robot; past :data:`_TURNING_RAD` it turns round
_BEHIND_RAD = math.radians(120)
_TURNING_RAD = math.radians(90)


class NetworkStepper:
    """Steps a fusion table's network one observation at a time into commands; optional heading
    noise makes it a network *teacher*. One per run: it carries the run's state from tick to tick."""

    def __init__(
        self,
        *,
        table: FusionTable,
        world: World | None,
        sensors: SensorParams,
        rng: np.random.Generator,
        heading_noise_rad: float = 0.0,
        robot: RobotParams = RobotParams(),
        safety: SafetyParams | None = SafetyParams(),
        geometry: ScanGeometry | None = None,
    ) -> None:
        # world None: a real robot (lfdfuse drive) — no map; targets only as its camera reports them
        if world is not None:
            check_table_world(table, world)
        self.table = table
        self.runtime = NetworkRuntime(table)
        self.sensors = sensors
        self.params = BehaviorParams(reach_m=sensors.camera.reach_m)
        #: what the stateful primitives carry from tick to tick
        self.behavior_state = BehaviorState(table.behaviors, self.params)
        self.rng = rng
        self.noise = heading_noise_rad
        self.robot = robot
        self.targets = world.target_names if world is not None else table.targets()
        self.geometry = geometry or sensors.laser.geometry  # the laser's beam layout
        self.sonar_angles = sensors.sonar.geometry.angles
        self.reached: list[tuple[str, int]] = []
        self.ticks = 0
        self.unseen_ticks = 0
        self.last: Decision | None = None
        self._turn = 0.0
        self._spin = 0.0  # the side of the last turn on the spot (0: the last tick drove on)
        self.safety = safety
        self.reflex_ticks = 0
        self.last_outputs: Any = None
        self.side: dict[str, list[tuple[float, float]]] = defaultdict(list)
        self._il = side_beam_index(self.geometry.angles, math.pi / 2)
        self._ir = side_beam_index(self.geometry.angles, -math.pi / 2)
        self.openings = OpeningSensor(self.geometry)  # landmark cues for sub-goal steps
        #: and for the landmarks sensed with their sectors held another way back
        self.lagged = [
            OpeningSensor(self.geometry, replace(self.openings.params, lag_m=lag))
            for lag in landmark_lags(table)
        ]
        self._odom: tuple[float, float, float] | None = None
        #: whether any step of the table has a landmark: only a landmark decides from the cues
        #: (without one the runtime's progress is never read), so a table without any senses none
        self._senses = self.runtime.senses
        # what every tick reads of the layout and the targets, looked up once
        self._ahead0 = ahead_bearings(self.geometry)
        self._target_names = tuple(self.targets)
        self._column = {name: i for i, name in enumerate(self._target_names)}
        self._no_targets = np.full((1, len(self.targets)), np.nan)
        self._unseen = unseen(len(self.targets))
        #: whether a behaviour of the table reads odometry (its spec says so): else no tick's
        #: observations carry the pose, which no primitive of the set would read
        self._odometry = any(
            spec is None or "odometry" in spec.inputs for spec in map(spec_of, table.behaviors)
        )
        self._step_names: dict[tuple[int, ...], str] = {}
        #: every request for help, in order (one when a condition begins, not every tick it lasts)
        self.help: list[HelpRequest] = []
        #: the request raised at the last tick (None: no new one), and the one standing now
        self.help_now: HelpRequest | None = None
        self.asking: HelpRequest | None = None

    @property
    def done(self) -> bool:
        return self.runtime.complete

    def _cues(self, observation: Observation) -> Cues:
        """Opening onsets from this scan, and the odometry increment since the last tick.

        Only relative motion is used (what wheel odometry gives), never the map position.
        """
        p = observation.pose
        step_m = turn = 0.0
        if self._odom is not None:
            x, y, th = self._odom
            step_m = math.hypot(p.x - x, p.y - y)
            turn = math.atan2(math.sin(p.theta - th), math.cos(p.theta - th))
        self._odom = (p.x, p.y, p.theta)
        ranges = observation.reading.ranges_m
        params = self.openings.params
        if kernels.AHEAD.ready() and type(ranges) is np.ndarray and ranges.dtype == np.float64:
            # ahead_range with no offset, its bearings looked up once
            ahead = float(kernels.AHEAD(ranges, self._ahead0, params.ahead_beam_rad))
        else:
            ahead = ahead_range(ranges, self.geometry, params)
        front_open = ahead >= params.ahead_open_m

        def sensed(sensor: OpeningSensor, lagged: tuple[tuple[float, Cues], ...] = ()) -> Cues:
            left, right = sensor.update(ranges, step_m, turn)
            ahead_open = sensor.ahead_m >= params.ahead_open_m
            beside = (sensor.tracker.inside[0], sensor.tracker.inside[1])
            return Cues(
                left, right, step_m, turn, sensor.held_turn_rad, ahead_open, beside, front_open, lagged
            )

        lagged = tuple((s.params.lag_m, sensed(s)) for s in self.lagged)
        return sensed(self.openings, lagged)

    def _ask(self, dec: Decision, t_ns: int) -> None:
        """Raise a :class:`HelpRequest` when a condition that needs help begins."""
        why = help_reason(dec)
        self.help_now = None
        if why is None:
            self.asking = None
            return
        step = self.step_name(dec.path)
        a = self.asking
        if a is None or (a.step, a.bac, a.why) != (step, dec.bac, why):
            self.asking = self.help_now = HelpRequest(t_ns, step, dec.bac, why)
            self.help.append(self.asking)

    def step_name(self, path: tuple[int, ...]) -> str:
        """:func:`~lfdfuse.network.runtime.step_name_of` the table's step at ``path`` (once per path)."""
        name = self._step_names.get(path)
        if name is None:
            name = self._step_names[path] = step_name_of(path, self.table)
        return name

    def _observations(self, observation: Observation) -> Observations:
        """This tick's :class:`Observations` (N = 1): what ``Observations.from_detections`` makes
        of it, the target columns looked up once."""
        reading = observation.reading
        if reading.detections:
            bearing, rng = self._no_targets.copy(), self._no_targets.copy()
            for d in reading.detections:
                j = self._column.get(d.name)
                if j is not None:
                    bearing[0, j], rng[0, j] = d.bearing_rad, d.range_m
        else:  # no target in sight (most ticks): the one all-NaN row, read-only (spec.unseen)
            bearing = rng = self._unseen
        ranges = reading.ranges_m[None, :]
        sonar = reading.sonar_m[None, :] if len(reading.sonar_m) else None  # a robot without sonar
        if sonar is not None and sonar.dtype != np.float64:
            sonar = np.asarray(sonar, dtype=np.float64)
        p = observation.pose
        return made_observations(
            ranges if ranges.dtype == np.float64 else np.asarray(ranges, dtype=np.float64),
            self.geometry,
            sonar,
            self.sonar_angles,
            self.sensors.sonar.max_range_m,
            self._target_names,
            bearing,
            rng,
            np.array([[p.x, p.y, p.theta]], dtype=np.float64) if self._odometry else None,
        )

    def command(self, observation: Observation) -> tuple[float, float]:
        reading = observation.reading
        obs = self._observations(observation)
        outputs = compute(obs, self.table.behaviors, self.params, self.behavior_state)
        reach = self.sensors.camera
        reached = {d.name for d in reading.detections if target_reached(d.range_m, reach)}
        dec = self.runtime.decide(outputs, reached, self._cues(observation) if self._senses else _NO_CUES)
        for goal in dec.achieved_now:
            self.reached.append((goal, self.ticks))
        self.last, self.last_outputs = dec, outputs
        self.ticks += 1
        self._ask(dec, observation.t_ns)
        if dec.step is None:
            return 0.0, 0.0
        self.unseen_ticks += dec.unseen
        self.side[self.step_name(dec.path)].append(
            (float(reading.ranges_m[self._il]), float(reading.ranges_m[self._ir]))
        )
        fx, fy = dec.fused.tolist()
        heading = math.atan2(fy, fx) if fx != 0.0 or fy != 0.0 else 0.0  # no pull at all: straight on
        if abs(heading) > _BEHIND_RAD and self._turn != 0.0:
            # the pull is behind the robot: commit to one turning direction while turning round,
            # instead of dithering as the behind-vector swings from side to side
            heading = math.copysign(abs(heading), self._turn)
        self._turn = math.copysign(1.0, heading) if abs(heading) > _TURNING_RAD else 0.0
        if self.noise > 0:
            heading += float(self.rng.normal(0.0, self.noise))
        if self.safety is not None:
            safe = free_heading(heading, reading.ranges_m, self.geometry.angles, self.safety)
            self.reflex_ticks += safe != heading
            heading = safe
        if abs(heading) >= _ON_THE_SPOT_RAD:
            # a turn on the spot: keep to the side the last one turned to. Where the pull swings
            # across the robot from tick to tick (two rows in turn, a wall straight ahead) a turn
            # left undone by a turn right leaves the robot where it is until the time runs out
            if self._spin != 0.0 and math.copysign(1.0, heading) != self._spin:
                heading = math.copysign(abs(heading), self._spin)
            self._spin = math.copysign(1.0, heading)
        else:
            self._spin = 0.0
        return heading_command(heading, self.robot.drive)
