"""The network as a command source: commands within the drive's limits, reproducible, and it
refuses only the targets that carry weight."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from lfdfuse.errors import ConfigError
from lfdfuse.network.stepper import NetworkStepper, check_table_world, weighted_targets
from lfdfuse.network.table import parse_table
from lfdfuse.sim.loop import run
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.world.model import load_world

TABLE: dict[str, Any] = {
    "format": "lfdfuse/fusion-table@1",
    "behaviors": ["avoid", "attract_red", "wander", "attract_blue", "attract_green"],
    "default_weights": {"avoid": 0.5, "wander": 0.5},
    "network": {
        "name": "t",
        "steps": [
            {
                "name": "reach-red",
                "goal": {"target": "red"},
                "default_weights": {"wander": 1.0, "attract_red": 1.0},
                "fusion": [{"bac": 0b0111, "weights": {"avoid": 0.2, "attract_red": 0.7, "wander": 0.1}}],
            },
            {
                "name": "reach-blue",
                "goal": {"target": "blue"},
                "fusion": [
                    {"bac": 0b11101, "weights": {"avoid": 0.3, "attract_blue": 0.7, "attract_green": 0.0}}
                ],
            },
        ],
    },
}


def test_weighted_targets_are_those_of_attract_behaviours_with_weight() -> None:
    assert weighted_targets(parse_table(TABLE)) == ["red", "blue"]
    zero_blue = copy.deepcopy(TABLE)
    zero_blue["network"]["steps"][1]["fusion"][0]["weights"] = {"avoid": 1.0, "attract_blue": 0.0}
    assert weighted_targets(parse_table(zero_blue)) == ["red"]


def test_a_world_lacking_a_weighted_target_is_refused_by_name() -> None:
    table = parse_table(TABLE)
    check_table_world(table, load_world("building"))  # red and blue: fine (green carries no weight)
    with pytest.raises(ConfigError, match=r"targets red, blue that world 'corridor' lacks \(it has: none\)"):
        check_table_world(table, load_world("corridor"))
    with pytest.raises(ConfigError):
        NetworkStepper(
            table=table, world=load_world("corridor"), sensors=SensorParams(), rng=np.random.default_rng(0)
        )


def _drive(seed: int, noise: float) -> tuple[np.ndarray, NetworkStepper]:
    world, sensors = load_world("building"), SensorParams()
    rng = np.random.default_rng(seed)
    driver = NetworkStepper(
        table=parse_table(TABLE), world=world, sensors=sensors, rng=rng, heading_noise_rad=noise
    )
    commands: list[tuple[float, float]] = []

    class _Tap:
        def record(self, obs: Any, command: tuple[float, float]) -> None:
            commands.append(command)

    run(Simulator(world, rng, sensors=sensors), driver, start=None, duration_s=4.0, sinks=[_Tap()])
    return np.array(commands), driver


@pytest.mark.parametrize("noise", [0.0, 0.3])
def test_commands_obey_the_drive_limits_and_replay_from_the_seed(noise: float) -> None:
    a, driver = _drive(7, noise)
    b, _ = _drive(7, noise)
    assert np.array_equal(a, b)
    drive = driver.robot.drive
    assert (a[:, 0] >= 0.0).all() and (a[:, 0] <= drive.v_max_mps + 1e-12).all()
    assert (np.abs(a[:, 1]) <= drive.omega_max_rps + 1e-12).all()
    assert driver.ticks == len(a)
    assert driver.last is not None
    assert all(goal in ("red", "blue", "attract_red", "attract_blue") for goal, _ in driver.reached)


def test_turns_on_the_spot_keep_to_the_side_they_began_on(monkeypatch: pytest.MonkeyPatch) -> None:
    """A pull that swings across the robot tick to tick (two rows in turn, a wall ahead) must not
    leave it turning left and right in place: it keeps turning the way it began."""
    import math

    import lfdfuse.network.stepper as driver_module

    swings = iter([math.radians(100.0), math.radians(-100.0)] * 40)
    monkeypatch.setattr(driver_module, "free_heading", lambda *args, **kwargs: next(swings))
    commands, _ = _drive(7, 0.0)
    assert (commands[:, 0] < 0.05).all()  # on the spot, or nearly
    assert (commands[:, 1] > 0).all(), commands[:, 1]


def _decisions(table: dict[str, Any], *, senses: bool, seconds: float = 20.0) -> list[tuple[Any, ...]]:
    world, sensors = load_world("building"), SensorParams()
    rng = np.random.default_rng(3)
    driver = NetworkStepper(table=parse_table(table), world=world, sensors=sensors, rng=rng)
    driver._senses = driver.runtime.senses = senses  # what they decide themselves: only for landmarks
    seen: list[tuple[Any, ...]] = []

    class _Tap:
        def record(self, obs: Any, command: tuple[float, float]) -> None:
            d = driver.last
            assert d is not None
            seen.append((command, d.path, d.bac, d.fused.tobytes(), d.weights, d.achieved_now))

    run(Simulator(world, rng, sensors=sensors), driver, start=None, duration_s=seconds, sinks=[_Tap()])
    return seen


def test_a_table_without_landmarks_decides_the_same_without_sensing_cues() -> None:
    """Only a landmark reads the opening cues: a table without one senses none, and every
    command and decision is the one it makes sensing them."""
    assert not NetworkStepper(
        table=parse_table(TABLE),
        world=load_world("building"),
        sensors=SensorParams(),
        rng=np.random.default_rng(0),
    )._senses
    assert _decisions(TABLE, senses=False) == _decisions(TABLE, senses=True)


def test_a_table_with_a_landmark_senses_cues() -> None:
    table = copy.deepcopy(TABLE)
    inner = {"name": "to", "goal": None, "landmark": {"opening": "left", "nth": 1}, "fusion": []}
    red = table["network"]["steps"][0]
    table["network"]["steps"][0] = {
        "name": "reach-red",
        "goal": {"target": "red"},
        "network": {
            "name": "reach-red",
            "steps": [inner, {k: v for k, v in red.items() if k != "goal"} | {"goal": {"target": "red"}}],
        },
    }
    driver = NetworkStepper(
        table=parse_table(table),
        world=load_world("building"),
        sensors=SensorParams(),
        rng=np.random.default_rng(0),
    )
    assert driver._senses


@pytest.mark.parametrize("follow", [False, True])
def test_a_ticks_observations_are_those_of_its_detections_in_sight_or_not(follow: bool) -> None:
    """What the stepper senses each tick is ``Observations.from_detections`` of the reading; a
    tick with no target in sight shares one all-NaN row, which no one may write to; the pose
    only where a behaviour reads odometry (``follow``)."""
    from lfdfuse.behaviors.spec import Observations

    world, sensors = load_world("building"), SensorParams()
    rng = np.random.default_rng(5)
    table = copy.deepcopy(TABLE)
    if follow:
        table["behaviors"].append("follow")
    driver = NetworkStepper(table=parse_table(table), world=world, sensors=sensors, rng=rng)
    assert driver._odometry == follow
    sim = Simulator(world, rng, sensors=sensors)
    seen = {True: 0, False: 0}
    obs = sim.reset(None)
    for _ in range(1500):
        got = driver._observations(obs)
        r = obs.reading
        want = Observations.from_detections(
            ranges_m=r.ranges_m[None, :],
            geometry=driver.geometry,
            detections=[r.detections],
            target_names=driver.targets,
            sonar_m=r.sonar_m[None, :],
            sonar_angles_rad=driver.sonar_angles,
            sonar_max_m=sensors.sonar.max_range_m,
            pose=np.array([obs.pose.as_tuple()]),
        )
        for f in ("ranges_m", "sonar_m", "target_bearing_rad", "target_range_m"):
            assert np.array_equal(getattr(got, f), getattr(want, f), equal_nan=True), f
        if follow:
            assert got.pose is not None and np.array_equal(got.pose, want.pose)
        else:
            assert got.pose is None  # no behaviour of the set reads it
        assert got.target_names == want.target_names
        in_sight = bool(r.detections)
        seen[in_sight] += 1
        if not in_sight:
            with pytest.raises(ValueError, match="read-only"):
                got.target_bearing_rad[0, 0] = 0.0
        obs = sim.step(*driver.command(obs))
    assert seen[True] and seen[False]  # both kinds of tick were checked
