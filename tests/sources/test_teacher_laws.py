"""The scripted teacher for itself: commands within the drive's limits, replayed from the seed;
its side-range probe agrees with brute force."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lfdfuse.control.command import DriveParams
from lfdfuse.errors import LfdError
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.sim.loop import run
from lfdfuse.sim.robot import RobotParams
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.sources.planner import Planner
from lfdfuse.sources.tasks import Leg
from lfdfuse.sources.teachers import StyleTeacher, side_range
from lfdfuse.world.model import load_world


@given(
    st.lists(st.floats(0.05, 8.0), min_size=5, max_size=60),
    st.floats(-math.pi, math.pi),
    st.floats(0.0, 0.5),
)
def test_side_range_is_the_nearest_return_in_the_window(
    ranges: list[float], angle: float, half: float
) -> None:
    geom = ScanGeometry(-math.pi / 2, math.pi / (len(ranges) - 1), len(ranges), 8.0)
    r = np.array(ranges)
    inside = [v for v, a in zip(ranges, geom.angles, strict=True) if abs(a - angle) <= half]
    assert side_range(r, geom, angle, half) == (min(inside) if inside else geom.max_range_m)


def _teach(seed: int, style: str) -> tuple[np.ndarray, StyleTeacher]:
    world, sensors, drive = load_world("building"), SensorParams(), DriveParams()
    rng = np.random.default_rng(seed)
    teacher = StyleTeacher(
        world=world,
        legs=[Leg("red", style)],
        planner=Planner(world, robot_radius_m=RobotParams().radius_m),
        geometry=sensors.laser.geometry,
        camera=sensors.camera,
        drive=drive,
        rng=rng,
    )
    commands: list[tuple[float, float]] = []

    class _Tap:
        def record(self, obs: object, command: tuple[float, float]) -> None:
            commands.append(command)

    run(Simulator(world, rng, sensors=sensors), teacher, start=None, duration_s=5.0, sinks=[_Tap()])
    return np.array(commands), teacher


@pytest.mark.parametrize("style", ["left", "slalom"])
def test_teacher_commands_obey_the_drive_and_replay_from_the_seed(style: str) -> None:
    a, teacher = _teach(11, style)
    b, _ = _teach(11, style)
    c, _ = _teach(12, style)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)  # the seed drives the teacher's imperfection
    d = teacher.drive
    assert (a[:, 0] >= 0.0).all() and (a[:, 0] <= d.v_max_mps + 1e-12).all()
    assert (np.abs(a[:, 1]) <= d.omega_max_rps + 1e-12).all()


def test_a_leg_to_a_target_the_world_lacks_is_refused() -> None:
    world, sensors = load_world("corridor"), SensorParams()
    with pytest.raises(LfdError, match="red"):
        StyleTeacher(
            world=world,
            legs=[Leg("red", "left")],
            planner=Planner(world, robot_radius_m=RobotParams().radius_m),
            geometry=sensors.laser.geometry,
            camera=sensors.camera,
            drive=DriveParams(),
            rng=np.random.default_rng(0),
        )
