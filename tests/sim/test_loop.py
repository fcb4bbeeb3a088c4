"""The one closed loop over the steppable simulator."""

from __future__ import annotations

import numpy as np
import pytest

from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.loop import run
from lfdfuse.sim.simulator import Simulator
from lfdfuse.world.model import load_world


class _Straight:
    """A command source that only drives straight on (into the wall ahead)."""

    done = False
    reached: list[tuple[str, int]] = []

    def command(self, obs: Observation) -> tuple[float, float]:
        return 0.4, 0.0


@pytest.mark.parametrize("stop", [False, True])
def test_collisions_are_counted_once_per_contact_and_can_end_the_run(stop: bool) -> None:
    sim = Simulator(load_world("corridor"), np.random.default_rng(0))
    summary = run(sim, _Straight(), start=Pose(28.0, 1.2, 0.0), duration_s=20.0, stop_on_collision=stop)
    assert summary.collisions == 1  # pressing on against the wall is one collision, not many
    assert summary.poses[:, 0].max() <= 30.0 - 0.25 + 1e-9
    assert (summary.duration_s < 6.0) if stop else (summary.duration_s == 20.0)


def test_step_is_reproducible_and_time_is_integer_nanoseconds() -> None:
    world = load_world("tee")
    runs = []
    for _ in range(2):
        sim = Simulator(world, np.random.default_rng(3))
        obs = [sim.reset()]
        for k in range(30):
            obs.append(sim.step(0.3, 0.4 * np.sin(k / 5)))
        runs.append(obs)
    for a, b in zip(*runs, strict=True):
        assert a.pose == b.pose and np.array_equal(a.reading.ranges_m, b.reading.ranges_m)
    assert [o.t_ns for o in runs[0]] == [k * 100_000_000 for k in range(31)]
    assert all(isinstance(o.t_ns, int) for o in runs[0])


def test_reset_refuses_a_start_inside_a_wall() -> None:
    from lfdfuse.errors import LfdError

    sim = Simulator(load_world("corridor"), np.random.default_rng(0))
    with pytest.raises(LfdError, match="start pose"):
        sim.reset(Pose(-5.0, -5.0, 0.0))
