"""The control core of a live run: decoded messages in, one command per fresh scan out.

No socket and no clock: the session calls :meth:`DriveCore.scan` with the wall time the scan
arrived, and the core answers with a :class:`Tick` (the command to send, clamped, and why) or
a :class:`Skip`. The network itself is the one ``execute`` runs
(:class:`~lfdfuse.network.stepper.NetworkStepper`: the same behaviours, runtime, vector →
command mapping and safety reflex), fed an :class:`~lfdfuse.robot.readings.Observation` built
from the robot's own sensing: the scan in the base frame, odometry for the landmark cues
(increments only), a camera's detections when the robot has one, no sonar.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from lfdfuse.behaviors.catalogue import needs
from lfdfuse.control.command import command_to_heading
from lfdfuse.drive.decode import LiveOdom, LiveScan, LiveTargets, LiveTf, LiveTwist
from lfdfuse.drive.frames import ScanFrame, TfTree
from lfdfuse.drive.safety import Limits, Watchdog
from lfdfuse.errors import ConfigError
from lfdfuse.network.stepper import NetworkStepper
from lfdfuse.network.table import FusionTable, Network
from lfdfuse.robot.mount import Mount
from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Observation, Reading
from lfdfuse.robot.ros import BASE_FRAMES
from lfdfuse.sim.robot import RobotParams
from lfdfuse.sim.sensors import SensorParams

#: scans to wait for a tf chain to the laser before assuming it sits at the base, facing forward
MOUNT_WAIT_SCANS = 20
_NO_SONAR = np.zeros(0)


# -- which behaviours the robot can run ---------------------------------------------------------


@dataclass(frozen=True)
class Inputs:
    """What the robot senses besides its laser."""

    camera: bool = False  # target detections (lfdfuse's simulated robot streams /targets)
    sonar: bool = False  # no live sonar decoding yet: sonar_avoid is never applicable


@dataclass(frozen=True)
class Applicability:
    have: tuple[str, ...]  # behaviours the robot can compute
    missing: dict[str, str]  # behaviour → the input it lacks
    steps: dict[str, float]  # step name → share of its weight on behaviours the robot has


def missing_input(name: str, inputs: Inputs) -> str:
    """'' when the robot can compute behaviour ``name``, else the input it lacks (from the
    catalogue's inputs of the behaviour; a live robot always has its laser and odometry)."""
    have = {"laser": True, "odometry": True, "camera": inputs.camera, "sonar": inputs.sonar}
    return next((need for need in sorted(needs(name)) if not have[need]), "")


def applicability(table: FusionTable, inputs: Inputs) -> Applicability:
    """Which behaviours apply, and for each step how much of its weight lies on them.

    A step's rows count by their samples (a hand-written row counts once), its default
    weights once. A step *needs a missing input* when less than half its weight is on
    behaviours the robot has.
    """
    missing = {b: why for b in table.behaviors if (why := missing_input(b, inputs))}
    shares: dict[str, float] = {}

    def walk(net: Network, prefix: str) -> None:
        for s in net.steps:
            name = f"{prefix}{s.name}"
            if s.network is not None:
                walk(s.network, f"{name}/")
                continue
            total = have = 0.0
            rows = [(r.weights, float(r.samples or 1)) for r in s.fusion]
            if s.default_weights:
                rows.append((s.default_weights, 1.0))
            for weights, n in rows:
                for b, w in weights.items():
                    total += n * w
                    have += n * w if b not in missing else 0.0
            shares[name] = have / total if total > 0 else 0.0

    walk(table.network, "")
    return Applicability(tuple(b for b in table.behaviors if b not in missing), missing, shares)


def check_applicable(app: Applicability) -> None:
    """Refuse a table whose every step needs an input the robot lacks."""
    if app.steps and all(share < 0.5 for share in app.steps.values()):
        lack = sorted(set(app.missing.values()))
        raise ConfigError(
            f"every step of the table needs {' and '.join(lack) or 'an input'} the robot lacks"
            f" (behaviours it has: {', '.join(app.have) or 'none'})"
        )


# -- the core -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Tick:
    """One fresh scan and what the network made of it."""

    obs: Observation  # stamped with the scan's stamp; the pose is odometry's
    network: tuple[float, float]  # the network's command, clamped
    robot: tuple[float, float] | None  # the robot's own latest command (recorded in --shadow)
    heading_error_deg: float | None  # network vs robot heading when the robot's is informative


@dataclass(frozen=True)
class Skip:
    """A scan that gave no command (stale, its mounting not yet known, foreign geometry)."""

    reason: str
    warn: bool  # worth telling the user (once)


@dataclass
class Agreement:
    """Running §12 heading error between the network and the robot's own commands (--shadow)."""

    errors_deg: list[float] = field(default_factory=list)
    ticks: int = 0  # ticks that had a robot command

    @property
    def mean_deg(self) -> float:
        return float(np.mean(self.errors_deg)) if self.errors_deg else math.nan


class DriveCore:
    """Turns decoded messages into commands (see the module docstring)."""

    def __init__(self, *, table: FusionTable, limits: Limits, inputs: Inputs, seed: int = 0) -> None:
        self.table = table
        self.limits = limits
        self.inputs = inputs
        base = RobotParams()
        self.robot = replace(
            base, drive=replace(base.drive, v_max_mps=limits.v_max_mps, omega_max_rps=limits.omega_max_rps)
        )
        self.rng = np.random.default_rng(seed)  # the driver draws nothing without heading noise
        self.watchdog = Watchdog()
        self.tf = TfTree()
        self.frame: ScanFrame | None = None
        self.mount: Mount | None = None
        self.mount_from = ""
        self.driver: NetworkStepper | None = None
        self.odom: LiveOdom | None = None
        self.targets: LiveTargets | None = None
        self.robot_cmd: tuple[float, float] | None = None
        self.agreement = Agreement()
        self._waited = 0
        self._k = 0

    # messages that only update what the core knows
    def on_tf(self, tf: LiveTf) -> None:
        self.tf.add(tf)

    def on_odom(self, odom: LiveOdom) -> None:
        self.odom = odom

    def on_targets(self, targets: LiveTargets) -> None:
        self.targets = targets

    def on_robot_cmd(self, twist: LiveTwist) -> None:
        self.robot_cmd = (twist.v_mps, twist.omega_rps)

    def reconnected(self) -> None:
        """A new connection: its stamps may restart; the network keeps its goal state."""
        self.watchdog.reset()
        self.odom = self.targets = None
        self.robot_cmd = None

    def _resolve(self, scan: LiveScan) -> Skip | None:
        if self.frame is not None:
            if not self.frame.matches(scan.record):
                return Skip("a scan whose beam geometry differs from the first: ignored", True)
            return None
        bases = tuple(
            dict.fromkeys(
                ([self.odom.base_frame] if self.odom and self.odom.base_frame else []) + list(BASE_FRAMES)
            )
        )
        found = self.tf.mount(scan.frame, bases)
        if found is None:
            self._waited += 1
            if self._waited < MOUNT_WAIT_SCANS:
                return Skip(f"waiting for tf from {scan.frame!r} to the base frame", False)
            found = (Mount(), f"unknown: no tf to {scan.frame!r}; assumed at the base, facing forward")
        self.mount, self.mount_from = found
        self.frame = ScanFrame.of(scan.record, self.mount)
        self.driver = NetworkStepper(
            table=self.table,
            world=None,
            sensors=SensorParams(),
            rng=self.rng,
            robot=self.robot,
            geometry=self.frame.geometry,
        )
        return None

    def scan(self, scan: LiveScan, now_s: float) -> Tick | Skip:
        """A scan arrived at ``now_s`` (monotonic seconds): the command to send, or why none."""
        why = self.watchdog.scan(scan.record.t_ns, now_s)
        if why:
            return Skip(f"stale scan: {why}", False)
        skip = self._resolve(scan)
        if skip is not None:
            return skip
        assert self.frame is not None and self.driver is not None
        t_ns = scan.record.t_ns
        o = self.odom
        pose = Pose(o.x, o.y, o.theta) if o is not None else Pose(0.0, 0.0, 0.0)
        dets = self.targets.detections if self._fresh_targets(t_ns) and self.targets else ()
        reading = Reading(self.frame.ranges(scan.record), _NO_SONAR, dets)
        obs = Observation(self._k, t_ns, pose, reading)
        self._k += 1
        v, w = self.limits.clamp(*self.driver.command(obs))
        self.watchdog.commanded(now_s)
        err = self._agree()
        return Tick(obs, (v, w), self.robot_cmd, err)

    def _fresh_targets(self, t_ns: int) -> bool:
        return self.targets is not None and abs(t_ns - self.targets.t_ns) <= 500_000_000

    def _agree(self) -> float | None:
        """The §12 heading error of this tick: the fused vector's heading against the heading
        the robot's own command demonstrates (informative commands only)."""
        if self.robot_cmd is None or self.driver is None or self.driver.last is None:
            return None
        self.agreement.ticks += 1
        dec = self.driver.last
        if dec.step is None:
            return None
        theta, ok = command_to_heading(
            np.array(self.robot_cmd[0]), np.array(self.robot_cmd[1]), self.robot.drive
        )
        if not bool(ok):
            return None
        fx, fy = float(dec.fused[0]), float(dec.fused[1])
        net = math.atan2(fy, fx) if (fx, fy) != (0.0, 0.0) else 0.0
        d = abs(math.degrees(math.atan2(math.sin(net - float(theta)), math.cos(net - float(theta)))))
        self.agreement.errors_deg.append(d)
        return d
