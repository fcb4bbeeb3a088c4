"""``simulate``: a scripted style teacher drives the simulator; the run is recorded as a demo."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.log.recorder import Recorder, provenance
from lfdfuse.log.writer import LogWriter
from lfdfuse.robot.pose import Pose
from lfdfuse.sim.loop import Progress, RunSummary, run
from lfdfuse.sim.robot import RobotParams
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.sources.planner import Planner
from lfdfuse.sources.tasks import Leg
from lfdfuse.sources.teachers import StyleTeacher, TeacherParams
from lfdfuse.sources.typist import KeyboardParams, KeyboardPerson, PressRecorder
from lfdfuse.world.parse import World, check_pose_free


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
    keys_period_s: float | None = None  # --keys: the teacher as a person at a keyboard (§9)
    #: --person and its parameters: the keyboard person's model (its period unless keys_period_s);
    #: None with keys_period_s is simulate --keys's own person, recorded as before
    person: KeyboardParams | None = None
    person_name: str = "custom"

    @property
    def keyboard(self) -> KeyboardParams | None:
        """The keyboard person's model, or None when the scripted teacher drives itself."""
        if self.person is None and self.keys_period_s is None:
            return None
        model = self.person or KeyboardParams()
        return model if self.keys_period_s is None else replace(model, period_s=self.keys_period_s)


def simulate(opts: SimulateOptions, *, out: str | Path, progress: Progress | None = None) -> RunSummary:
    """Run a scripted teacher in a world and record the demonstration to ``out``."""
    if opts.duration_s <= 0:
        raise ConfigError("duration must be positive")
    if opts.keys_period_s is not None and not (0.05 <= opts.keys_period_s <= 60.0):
        raise ConfigError(
            f"--keys must be a key period between 0.05 and 60 seconds, got {opts.keys_period_s}"
        )
    person = opts.keyboard
    if person is not None:
        try:
            person.check()
        except ValueError as exc:
            raise ConfigError(str(exc)) from None
    rng = np.random.default_rng(opts.seed)
    params = SensorParams().with_noise(opts.sensor_noise_m) if opts.sensor_noise_m > 0 else SensorParams()
    start = opts.start or Pose(*opts.world.start)
    check_pose_free(opts.world, start.as_tuple(), what="start pose", radius=opts.robot.radius_m)
    planner = Planner(opts.world, robot_radius_m=opts.robot.radius_m)
    tparams = opts.teacher
    if person is not None and person.corner_m > 0:
        ahead = round(person.corner_m / planner.params.resolution_m)
        tparams = replace(tparams, lookahead_cells=tparams.lookahead_cells + ahead)
    teacher = StyleTeacher(
        world=opts.world,
        legs=opts.legs,
        planner=planner,
        geometry=params.laser.geometry,
        camera=params.camera,
        drive=opts.robot.drive,
        rng=rng,
        params=tparams,
    )
    source: StyleTeacher | KeyboardPerson = teacher
    extra: dict[str, str] = {}
    if person is not None:
        source = KeyboardPerson(
            teacher,
            drive=opts.robot.drive,
            dt_s=opts.robot.dt_s,
            rng=np.random.default_rng([opts.seed, 19]),  # its own stream: the teacher's is unchanged
            params=person,
            beam_angles_rad=params.laser.geometry.angles,
        )
        extra = {"input": f"keys:{person.period_s!r}"}
        if opts.person is not None:
            extra |= {"person": opts.person_name, "person_model": person.describe()}
    meta = provenance(
        command="simulate",
        seed=opts.seed,
        world=opts.world,
        sensors=params,
        teacher=opts.teacher_name if person is None else f"keyboard:{opts.teacher_name}",
        duration_s=repr(opts.duration_s),
        start=",".join(repr(v) for v in start.as_tuple()),
        task=";".join(f"{leg.target or '-'}:{leg.style}" for leg in opts.legs),
    )
    meta.update(extra)
    sim = Simulator(opts.world, rng, params, opts.robot)
    with LogWriter(out, metadata=meta) as log:
        sinks: list[Recorder | PressRecorder] = [Recorder(log, world=opts.world, sensors=params)]
        if isinstance(source, KeyboardPerson):
            sinks.append(PressRecorder(log, source))
        return run(
            sim,
            source,
            start=start,
            duration_s=opts.duration_s,
            sinks=sinks,
            progress=progress,
            out=str(out),
        )
