from __future__ import annotations

import numpy as np

from lfdfuse.robot.pose import Pose
from lfdfuse.sim.robot import RobotParams, move
from lfdfuse.sim.sensors import SensorParams, Sensors
from lfdfuse.world.model import load_world
from lfdfuse.world.raycast import RayCaster


def test_random_driving_never_passes_through_walls() -> None:
    world = load_world("obstacles")
    caster = RayCaster(world.segments)
    params = RobotParams()
    for seed in range(5):
        rng = np.random.default_rng(seed)
        pose = Pose(*world.start)
        blocked = 0
        for _ in range(1500):
            v = rng.uniform(0.0, 0.6)
            w = rng.uniform(-2.5, 2.5)
            pose, b = move(pose, v, w, params=params, caster=caster)
            blocked += b
            assert caster.clearance(pose.x, pose.y) >= params.radius_m
            assert 0.0 < pose.x < 20.0 and 0.0 < pose.y < 3.0
        assert blocked > 0  # random driving in a 3 m corridor does hit walls


def test_limits_are_applied() -> None:
    world = load_world("building")
    caster = RayCaster(world.segments)
    p = RobotParams()
    new, blocked = move(Pose(5.0, 1.2, 0.0), 10.0, 10.0, params=p, caster=caster)
    assert not blocked
    assert abs(new.theta) <= p.drive.omega_max_rps * p.dt_s + 1e-12
    assert np.hypot(new.x - 5.0, new.y - 1.2) <= p.drive.v_max_mps * p.dt_s + 1e-12


def test_camera_sees_targets_in_view_and_line_of_sight_only() -> None:
    world = load_world("building")
    sensors = Sensors(world, SensorParams())
    rng = np.random.default_rng(0)
    red = world.target("red")
    facing = sensors.sense(Pose(red.x, red.y - 3.0, np.pi / 2), rng)
    assert [d.name for d in facing.detections] == ["red"]
    assert abs(facing.detections[0].range_m - 3.0) < 1e-9 and abs(facing.detections[0].bearing_rad) < 1e-9
    away = sensors.sense(Pose(red.x, red.y - 3.0, -np.pi / 2), rng)
    assert away.detections == ()
    behind_wall = sensors.sense(Pose(30.0, 8.0, 0.0), rng)  # inside the wall block: no line of sight
    assert behind_wall.detections == ()


def test_sensor_noise_comes_from_the_seed() -> None:
    world = load_world("corridor")
    sensors = Sensors(world, SensorParams().with_noise(0.02))
    a = sensors.sense(Pose(*world.start), np.random.default_rng(5)).ranges_m
    b = sensors.sense(Pose(*world.start), np.random.default_rng(5)).ranges_m
    c = sensors.sense(Pose(*world.start), np.random.default_rng(6)).ranges_m
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert (a >= 0).all() and (a <= 8.0).all()
