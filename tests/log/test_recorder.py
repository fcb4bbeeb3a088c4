"""The recorder: every tick of the loop is in the log, as the loop saw it, with its provenance."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from lfdfuse.log.reader import file_info, read_run
from lfdfuse.log.recorder import Recorder, provenance
from lfdfuse.log.writer import PROVENANCE, LogWriter
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.loop import run
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.world.model import load_world


class _Weave:
    """Drives a slow weave (a command that depends on the tick, so misaligned ticks show)."""

    done = False
    reached: list[tuple[str, int]] = []

    def command(self, obs: Observation) -> tuple[float, float]:
        return 0.3, 0.4 * math.sin(obs.k / 4)


def test_every_tick_is_recorded_on_one_clock(tmp_path: Path) -> None:
    world, sensors = load_world("building"), SensorParams()
    meta = provenance(command="test", seed=5, world=world, sensors=sensors, extra_key="x")
    out = tmp_path / "r.mcap"
    with LogWriter(out, metadata=meta) as log:
        sim = Simulator(world, np.random.default_rng(5), sensors=sensors)
        summary = run(
            sim, _Weave(), start=None, duration_s=3.0, sinks=[Recorder(log, world=world, sensors=sensors)]
        )
    r = read_run(out)
    assert len(r) == summary.steps == 31
    assert np.array_equal(r.t_ns, np.arange(31, dtype=np.int64) * 100_000_000)
    assert np.array_equal(r.cmd_t_ns, r.t_ns)
    np.testing.assert_allclose(r.cmd_omega_rps, 0.4 * np.sin(np.arange(31) / 4))
    assert r.pose is not None
    np.testing.assert_allclose(r.pose, summary.poses, atol=1e-9)
    assert r.ranges_m.shape == (31, sensors.laser.beams)
    assert r.world_yaml == world.source
    info = file_info(out)
    assert info.metadata[PROVENANCE] == dict(sorted(meta.items()))
    assert set(info.channels) == {"/scan", "/sonar", "/pose", "/tf", "/targets", "/cmd_vel", "/world"}


def test_provenance_floats_round_trip_through_their_text() -> None:
    world, sensors = load_world("corridor"), SensorParams()
    meta = provenance(command="simulate", seed=3, world=world, sensors=sensors, dt_s=0.05)
    assert meta["tool"] == "lfdfuse" and meta["seed"] == "3" and meta["world"] == world.name
    assert float(meta["laser_max_range_m"]) == sensors.laser.max_range_m
    assert float(meta["sonar_max_range_m"]) == sensors.sonar.max_range_m
    assert float(meta["camera_reach_m"]) == sensors.camera.reach_m
    assert float(meta["dt_s"]) == 0.05
    assert all(isinstance(v, str) for v in meta.values())
