"""The control core: the network of ``execute``, fed from decoded messages; which tables it runs."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import orjson
import pytest

from lfdfuse.drive.core import DriveCore, Inputs, Skip, Tick, applicability, check_applicable
from lfdfuse.drive.decode import LiveOdom, LiveTargets, LiveTwist
from lfdfuse.drive.decoders import decoder_for
from lfdfuse.drive.foxglove.wire import ServerChannel
from lfdfuse.drive.safety import Limits
from lfdfuse.errors import ConfigError
from lfdfuse.log import messages as msg
from lfdfuse.network.stepper import NetworkStepper
from lfdfuse.network.table import FusionRow, FusionTable, Network, Step, load_table
from lfdfuse.robot.readings import Reading
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.world.model import load_world

SCAN = decoder_for(ServerChannel(1, "/scan", "json", "foxglove.LaserScan", "jsonschema", ""))


def test_the_core_commands_exactly_what_execute_would(keep_left: Path) -> None:
    """Same observations (as they travel: ranges to the millimetre) → the same commands, tick for tick."""
    table = load_table(keep_left)
    world = load_world("building")
    params = SensorParams()
    lim = Limits(0.4, math.radians(100))
    core = DriveCore(table=table, limits=lim, inputs=Inputs(camera=True))
    ref = NetworkStepper(table=table, world=world, sensors=params, rng=np.random.default_rng(0))
    sim = Simulator(world, np.random.default_rng(0), params)
    obs = sim.reset(None)
    moved = 0.0
    for k in range(150):
        t = (k + 1) * 100_000_000
        sent = replace(
            obs,
            t_ns=t,
            reading=Reading(np.round(obs.reading.ranges_m, 3), np.zeros(0), obs.reading.detections),
        )
        want = ref.command(sent)
        p = obs.pose
        core.on_odom(LiveOdom(t, p.x, p.y, p.theta, "base_link"))
        core.on_targets(LiveTargets(t, obs.reading.detections))
        tick = core.scan(
            SCAN(orjson.dumps(msg.laser_scan(t, obs.reading.ranges_m, params.laser.geometry))), k * 0.1
        )
        assert isinstance(tick, Tick)
        assert tick.network == want, k
        moved += want[0] * 0.1
        obs = sim.step(*want)
    assert moved > 3.0 and sim.collisions == 0


def _table(weights: list[dict[str, float]]) -> FusionTable:
    names = ("avoid", "attract_red", "wander_left", "sonar_avoid")
    steps = tuple(Step(f"s{i}", None, (FusionRow(1, w, samples=10),)) for i, w in enumerate(weights))
    return FusionTable(names, {"avoid": 1.0}, Network("n", steps))


def test_a_table_needing_only_missing_inputs_is_refused() -> None:
    app = applicability(_table([{"attract_red": 0.9, "avoid": 0.1}, {"sonar_avoid": 1.0}]), Inputs())
    assert app.missing == {"attract_red": "camera", "sonar_avoid": "sonar"}
    assert app.have == ("avoid", "wander_left")
    with pytest.raises(ConfigError, match="every step of the table needs camera and sonar"):
        check_applicable(app)
    # one runnable step is enough; a camera makes attract applicable
    check_applicable(
        applicability(_table([{"attract_red": 1.0}, {"wander_left": 0.8, "sonar_avoid": 0.2}]), Inputs())
    )
    check_applicable(applicability(_table([{"attract_red": 1.0}]), Inputs(camera=True)))


def test_scans_before_the_mounting_is_known_wait_then_assume_the_base(keep_left: Path) -> None:
    core = DriveCore(table=load_table(keep_left), limits=Limits(0.4, 1.0), inputs=Inputs())
    geom = SensorParams().laser.geometry
    scan = orjson.loads(orjson.dumps(msg.laser_scan(0, np.full(geom.count, 2.0), geom)))
    scan["frame_id"] = "laser"
    results = []
    for k in range(25):
        scan["timestamp"] = {"sec": k, "nsec": 0}
        results.append(core.scan(SCAN(orjson.dumps(scan)), float(k)))
    skips = [r for r in results if isinstance(r, Skip)]
    assert 10 <= len(skips) < 25 and all("waiting for tf" in s.reason for s in skips)
    assert isinstance(results[-1], Tick) and "assumed at the base" in core.mount_from


def test_shadow_agreement_is_the_heading_error(keep_left: Path) -> None:
    core = DriveCore(table=load_table(keep_left), limits=Limits(0.4, math.radians(100)), inputs=Inputs())
    geom = SensorParams().laser.geometry
    ranges = np.full(geom.count, 8.0)
    ranges[geom.count // 2 :] = 0.6  # a wall on the left
    core.on_robot_cmd(LiveTwist(0.0, 0.0))  # standing still: no heading information
    tick = core.scan(SCAN(orjson.dumps(msg.laser_scan(1, ranges, geom))), 0.0)
    assert isinstance(tick, Tick) and tick.heading_error_deg is None and core.agreement.ticks == 1
    core.on_robot_cmd(LiveTwist(0.4, 0.0))  # straight ahead
    tick = core.scan(SCAN(orjson.dumps(msg.laser_scan(2, ranges, geom))), 0.1)
    assert isinstance(tick, Tick) and tick.heading_error_deg is not None
    dec = core.driver.last if core.driver else None
    assert dec is not None
    assert tick.heading_error_deg == pytest.approx(abs(math.degrees(math.atan2(dec.fused[1], dec.fused[0]))))
    assert core.agreement.mean_deg == pytest.approx(tick.heading_error_deg)


def test_scans_the_network_cannot_use_leave_the_robot_blind(keep_left: Path) -> None:
    """A scanner that changes its beam layout mid-run is not driven on: the watchdog stops the robot."""
    core = DriveCore(table=load_table(keep_left), limits=Limits(0.4, 1.0), inputs=Inputs())
    geom = SensorParams().laser.geometry
    tick = core.scan(SCAN(orjson.dumps(msg.laser_scan(1, np.full(geom.count, 3.0), geom))), 0.0)
    assert isinstance(tick, Tick) and not core.watchdog.blind(0.4)
    other = replace(geom, count=geom.count - 10)
    for k in range(2, 10):
        t = k * 100_000_000
        skip = core.scan(SCAN(orjson.dumps(msg.laser_scan(t, np.full(other.count, 3.0), other))), 0.1 * k)
        assert isinstance(skip, Skip) and skip.warn and "beam geometry" in skip.reason
    assert core.watchdog.blind(0.9)
