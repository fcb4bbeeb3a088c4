"""Behaviours on real scanners: any beam geometry gives what the simulated laser gives."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lfdfuse.behaviors.primitives import BASE_BEHAVIORS, Observations, compute, distinct_beams
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.sim.sensors import LaserParams

NAMES = [n for n in BASE_BEHAVIORS if n != "sonar_avoid"]
SIM = LaserParams().geometry  # 181 beams over the front 180°, 8 m


def _obs(ranges: np.ndarray, geom: ScanGeometry) -> Observations:
    return Observations.from_detections(
        ranges_m=ranges, geometry=geom, detections=[()] * len(ranges), target_names=[]
    )


def _sim_scans(n: int = 200, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.2, 9.0, (n, SIM.count))
    return np.where(r > SIM.max_range_m, SIM.max_range_m, r)


def _same(a: Observations, b: Observations) -> None:
    oa, ob = compute(a, NAMES), compute(b, NAMES)
    np.testing.assert_array_equal(oa.applicable, ob.applicable)
    np.testing.assert_array_equal(oa.bac, ob.bac)
    np.testing.assert_allclose(oa.vectors, ob.vectors, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("start_deg", "count", "offset"),
    [
        (-180.0, 360, 90),  # a 360° scanner at 1°: the front half is beams 90…270
        (0.0, 360, -90),  # the same scanner starting straight ahead (the Neato after import)
        (-180.0, 361, 90),  # 361 beams over 360°, first and last at the same bearing
    ],
)
def test_a_360_scanner_matches_the_simulated_laser(start_deg: float, count: int, offset: int) -> None:
    sim = _sim_scans()
    geom = ScanGeometry(math.radians(start_deg), math.pi / 180, count, SIM.max_range_m)
    wide = np.full((len(sim), count), SIM.max_range_m)  # no return behind the robot
    idx = (np.arange(SIM.count) + offset) % 360
    wide[:, idx] = sim
    if count == 361:
        wide[:, 360] = wide[:, 0]
    _same(_obs(sim, SIM), _obs(wide, geom))


def test_a_720_beam_scanner_at_the_same_bearings_matches_too() -> None:
    sim = _sim_scans()
    geom = ScanGeometry(-math.pi, math.pi / 360, 720, SIM.max_range_m)
    wide = np.full((len(sim), 720), SIM.max_range_m)
    wide[:, 180:541:2] = sim  # every other beam of the front half at the simulated bearings
    a, b = compute(_obs(sim, SIM), NAMES), compute(_obs(wide, geom), NAMES)
    np.testing.assert_array_equal(a.applicable, b.applicable)
    for name in ("avoid", "wall_attract_left", "wall_attract_right", "circular_avoid_left"):
        k = NAMES.index(name)
        np.testing.assert_allclose(a.vectors[:, k], b.vectors[:, k], atol=1e-12)


def test_rear_returns_push_avoid_only() -> None:
    geom = ScanGeometry(-math.pi, math.pi / 180, 360, 8.0)
    r = np.full((1, 360), 8.0)
    r[0, 0] = 0.5  # straight behind
    out = compute(_obs(r, geom), NAMES)
    assert out.applicable[0].tolist() == [n == "avoid" or n.startswith("wander") for n in NAMES]
    assert out.vectors[0, NAMES.index("avoid"), 0] > 0.7  # pushed forward


def test_no_sonar_or_camera_means_never_applicable() -> None:
    geom = ScanGeometry(-math.pi, math.pi / 180, 360, 8.0)
    obs = _obs(np.full((4, 360), 0.5), geom)
    out = compute(obs, ["sonar_avoid", "avoid"])
    assert not out.applicable[:, 0].any() and out.applicable[:, 1].all()


def test_distinct_beams() -> None:
    assert distinct_beams(ScanGeometry(-math.pi, math.pi / 180, 361, 5.0)).sum() == 360
    assert distinct_beams(ScanGeometry(-math.pi, math.pi / 180, 360, 5.0)).all()
    assert distinct_beams(ScanGeometry(-math.pi / 2, math.pi / 180, 181, 5.0)).all()
    assert distinct_beams(ScanGeometry(0.0, 0.0, 0, 5.0)).shape == (0,)
