"""Laws of the behaviour primitives over random scans and scanner geometries."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.behaviors.primitives import (
    BASE_BEHAVIORS,
    PRESETS,
    BehaviorParams,
    Observations,
    compute,
    resolve_behaviors,
)
from lfdfuse.errors import ConfigError
from lfdfuse.robot.readings import Detection, ScanGeometry

ALL = [*BASE_BEHAVIORS, "attract_red"]
SONAR = ScanGeometry(math.pi / 2, math.pi / 7, 8, 5.0)


def _obs(
    ranges: np.ndarray,
    geom: ScanGeometry,
    sonar: np.ndarray | None = None,
    red: tuple[float, float] | None = None,
) -> Observations:
    n = len(ranges)
    dets = [() if red is None else (Detection("red", red[0], red[1]),) for _ in range(n)]
    return Observations.from_detections(
        ranges_m=ranges,
        geometry=geom,
        detections=dets,
        target_names=["red"],
        sonar_m=sonar,
        sonar_angles_rad=SONAR.angles if sonar is not None else None,
        sonar_max_m=5.0,
    )


def _messy_ranges(rng: np.random.Generator, n: int, b: int, max_range: float) -> np.ndarray:
    r = rng.uniform(0.05, max_range * 1.2, (n, b))
    kind = rng.integers(0, 8, (n, b))
    r[kind == 0] = np.inf
    r[kind == 1] = np.nan
    r[kind == 2] = 0.0
    r[kind == 3] = max_range
    r[kind == 4] = rng.uniform(0.1, 2.0, (kind == 4).sum())  # plenty of near returns
    return r


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    count=st.integers(1, 720),
    fov=st.sampled_from([math.pi, 4 * math.pi / 3, 2 * math.pi * 359 / 360, math.radians(90)]),
    offset=st.floats(-0.5, 0.5),
)
def test_vectors_are_finite_in_the_unit_disc_and_zero_when_inapplicable(
    seed: int, count: int, fov: float, offset: float
) -> None:
    rng = np.random.default_rng(seed)
    inc = fov / max(count - 1, 1)
    geom = ScanGeometry(-fov / 2 + offset, inc, count, 8.0)
    ranges = _messy_ranges(rng, 5, count, 8.0)
    sonar = _messy_ranges(rng, 5, 8, 5.0)
    out = compute(_obs(ranges, geom, sonar, red=(0.3, 2.0)), ALL)
    assert np.isfinite(out.vectors).all()
    norms = np.hypot(out.vectors[..., 0], out.vectors[..., 1])
    assert (norms <= 1.0 + 1e-9).all()
    assert (norms[~out.applicable] == 0.0).all()


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), count=st.sampled_from([181, 361, 91, 240]))
def test_mirror_symmetry(seed: int, count: int) -> None:
    rng = np.random.default_rng(seed)
    geom = ScanGeometry(-math.pi / 2, math.pi / (count - 1), count, 8.0)
    ranges = _messy_ranges(rng, 4, count, 8.0)
    sonar = _messy_ranges(rng, 4, 8, 5.0)
    bearing = float(rng.uniform(-0.7, 0.7))
    a = compute(_obs(ranges, geom, sonar, red=(bearing, 3.0)), ALL)
    b = compute(_obs(ranges[:, ::-1], geom, sonar[:, ::-1], red=(-bearing, 3.0)), ALL)
    mirror = {n: n.replace("_left", "_tmp").replace("_right", "_left").replace("_tmp", "_right") for n in ALL}
    for i, name in enumerate(ALL):
        j = ALL.index(mirror[name])
        assert np.array_equal(a.applicable[:, i], b.applicable[:, j]), name
        assert np.allclose(a.vectors[:, i, 0], b.vectors[:, j, 0], atol=1e-9), name
        assert np.allclose(a.vectors[:, i, 1], -b.vectors[:, j, 1], atol=1e-9), name


@settings(max_examples=100, deadline=None)
@given(beam=st.integers(0, 180), dist=st.floats(0.1, 1.99), seed=st.integers(0, 1000))
def test_avoid_points_away_from_the_nearest_return(beam: int, dist: float, seed: int) -> None:
    geom = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 8.0)
    rng = np.random.default_rng(seed)
    r = rng.uniform(2.0, 8.0, (1, 181))  # every other return beyond d_max
    r[0, beam] = dist
    out = compute(_obs(r, geom), ["avoid"])
    v = out.vectors[0, 0]
    a = geom.angles[beam]
    assert out.applicable[0, 0]
    assert v[0] * math.cos(a) + v[1] * math.sin(a) < 0  # away from the nearest return
    assert np.hypot(*v) == pytest.approx((2.0 - dist) / 2.0)  # as strong as the nearest return


def test_live_and_offline_give_identical_results() -> None:
    rng = np.random.default_rng(1)
    geom = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 8.0)
    ranges = _messy_ranges(rng, 50, 181, 8.0)
    sonar = _messy_ranges(rng, 50, 8, 5.0)
    names = resolve_behaviors("full", ["red"])
    whole = compute(_obs(ranges, geom, sonar, red=(0.2, 1.0)), names)
    for k in range(50):
        one = compute(_obs(ranges[k : k + 1], geom, sonar[k : k + 1], red=(0.2, 1.0)), names)
        assert np.array_equal(one.vectors[0], whole.vectors[k])
        assert np.array_equal(one.applicable[0], whole.applicable[k])
        assert np.array_equal(one.goal_met[0], whole.goal_met[k])


def test_no_return_sentinels_mean_open_space() -> None:
    geom = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 8.0)
    for sentinel in (np.inf, np.nan, 0.0, 8.0, 9.5):
        out = compute(_obs(np.full((1, 181), sentinel), geom), ["avoid", "wander", "wall_attract_left"])
        assert out.applicable[0].tolist() == [False, True, False]
        assert out.vectors[0, 1, 0] == pytest.approx(
            2 * 90 / 181 * 2 / math.pi * 181 / 181, rel=0.05
        )  # mean of cosines ≈ 2/π


def test_beams_outside_a_sector_are_ignored_on_a_360_scanner() -> None:
    geom = ScanGeometry(-math.pi, 2 * math.pi / 360, 360, 12.0)
    r = np.full((1, 360), np.inf)
    behind = np.abs(geom.angles) > math.radians(100)
    r[0, behind] = 0.5  # a wall right behind the robot
    out = compute(_obs(r, geom), ["avoid", "wall_attract_left", "wall_attract_right", "wander_left"])
    assert out.applicable[0].tolist() == [True, False, False, True]


def test_attract_goal_and_presets() -> None:
    geom = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 8.0)
    r = np.full((2, 181), 8.0)
    far = compute(_obs(r[:1], geom, red=(0.5, 3.0)), ["attract_red"], BehaviorParams(reach_m=0.75))
    near = compute(_obs(r[:1], geom, red=(0.5, 0.5)), ["attract_red"], BehaviorParams(reach_m=0.75))
    assert far.applicable[0, 0] and not far.goal_met[0, 0] and near.goal_met[0, 0]
    assert np.allclose(far.vectors[0, 0], [math.cos(0.5), math.sin(0.5)])
    assert resolve_behaviors("scenario3", ["red", "blue"])[:3] == ["avoid", "attract_red", "attract_blue"]
    assert len(resolve_behaviors("full", [])) == len(PRESETS["full"]) - 1
    with pytest.raises(ConfigError, match="unknown behaviour 'fly'.*wander_left"):
        resolve_behaviors("avoid,fly", ["red"])
    with pytest.raises(ConfigError, match="attract_green"):
        resolve_behaviors("attract_green", ["red"])


def test_bac_is_the_bit_mask() -> None:
    geom = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 8.0)
    r = np.full((1, 181), 8.0)
    r[0, 170:] = 1.0  # a wall on the left only
    out = compute(
        _obs(r, geom), ["avoid", "wander_left", "wander_right", "wall_attract_left", "wall_attract_right"]
    )
    assert out.applicable[0].tolist() == [True, True, True, True, False]
    assert int(out.bac[0]) == 1 + 2 + 4 + 8


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), preset=st.sampled_from(["scenario1", "scenario3", "full"]))
def test_a_tick_that_sees_no_target_computes_as_its_nan_rows_do(seed: int, preset: str) -> None:
    """The shared read-only row of a live tick with no target in sight (``spec.unseen``, which
    ``compute`` knows by identity and skips the targets of) gives the outputs of NaN rows."""
    from dataclasses import replace

    from lfdfuse.behaviors.spec import sees_none, unseen

    g = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 30.0)
    rng = np.random.default_rng(seed)
    names = resolve_behaviors(preset, ["red", "blue"])
    nan = np.full((1, 2), np.nan)
    base = Observations.from_detections(
        ranges_m=_messy_ranges(rng, 1, 181, 30.0),
        geometry=g,
        detections=[()],
        target_names=["red", "blue"],
        sonar_m=rng.uniform(0.1, 6.0, (1, 8)),
        sonar_angles_rad=SONAR.angles,
        sonar_max_m=5.0,
    )
    row = unseen(2)
    shared = replace(base, target_bearing_rad=row, target_range_m=row)
    plain = replace(base, target_bearing_rad=nan, target_range_m=nan.copy())
    assert sees_none(shared) and not sees_none(plain) and unseen(2) is row and not row.flags.writeable
    a, b = compute(shared, names), compute(plain, names)
    for f in ("vectors", "applicable", "goal_met"):
        assert getattr(a, f).tobytes() == getattr(b, f).tobytes()
