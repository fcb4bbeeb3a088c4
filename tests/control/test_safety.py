"""The safety reflex: the free heading nearest the wanted one, never into a return just ahead."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lfdfuse.control import safety
from lfdfuse.control.safety import BLOCKED, SafetyParams, free_heading, free_heading_reference
from lfdfuse.kernels.jit import Warmup

ANGLES = np.radians(np.arange(-90.0, 90.5, 1.0))
P = SafetyParams()


def blocked(heading: float, ranges: np.ndarray) -> bool:
    d = ANGLES - heading
    along, lateral = ranges * np.cos(d), np.abs(ranges * np.sin(d))
    return bool(((along > 0) & (along < P.lookahead_m) & (lateral < P.halfwidth_m)).any())


def test_a_free_heading_is_kept() -> None:
    ranges = np.full(ANGLES.shape, 8.0)
    assert free_heading(0.3, ranges, ANGLES, P) == 0.3


def test_a_wall_just_ahead_turns_the_robot_away() -> None:
    ranges = np.full(ANGLES.shape, 8.0)
    ranges[np.abs(ANGLES) < math.radians(20)] = 0.4  # an obstacle dead ahead
    h = free_heading(0.0, ranges, ANGLES, P)
    assert h != 0.0 and not blocked(h, ranges)


def test_boxed_in_it_turns_on_the_spot() -> None:
    ranges = np.full(ANGLES.shape, 0.3)
    assert abs(free_heading(0.1, ranges, ANGLES, P)) > math.pi / 2


@settings(max_examples=150, deadline=None)
@given(st.floats(-1.4, 1.4), st.integers(0, 2**31 - 1))
def test_the_reflex_never_picks_a_blocked_heading_and_stays_within_90_degrees(want: float, seed: int) -> None:
    rng = np.random.default_rng(seed)
    ranges = rng.uniform(0.2, 8.0, ANGLES.shape)
    ranges[rng.random(ANGLES.shape) < 0.3] = np.inf  # no return
    h = free_heading(want, ranges, ANGLES, P)
    if abs(h) <= math.pi / 2 + 1e-9 and abs(h - want) <= math.pi / 2 + 1e-9:
        assert not blocked(h, np.where(np.isfinite(ranges), ranges, 0.0))
    else:  # nothing free within ±90° of the wanted heading: a turn on the spot
        assert abs(h) > math.pi / 2


def _scan(rng: np.random.Generator, n: int) -> np.ndarray:
    """Ranges with returns near the strip, beyond it, missing, zero, negative and NaN."""
    r = rng.uniform(0.05, 3.0, n)
    near = rng.uniform(size=n) < 0.3
    r[near] = rng.uniform(0.0, 0.9, near.sum())
    for value, share in ((np.inf, 0.1), (np.nan, 0.05), (0.0, 0.03), (-0.5, 0.02), (-0.0, 0.02)):
        r[rng.uniform(size=n) < share] = value
    return r


@pytest.fixture
def compiled_from_the_first_call(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(safety, "_WARMUP", Warmup(0))  # not the numpy answers of a short run


@pytest.mark.skipif(not BLOCKED.ready(), reason="numba kernels unavailable here")
@pytest.mark.usefixtures("compiled_from_the_first_call")
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    st.integers(0, 2**32 - 1),
    st.floats(-math.pi, math.pi),
    st.sampled_from([ANGLES, np.radians(np.arange(-180.0, 180.5, 1.0)), np.linspace(-2.3, 2.3, 37)]),
)
def test_the_compiled_strip_test_gives_the_references_heading(
    seed: int, heading: float, angles: np.ndarray
) -> None:
    """Free or turned away, bit for bit: the compiled first test (and the blocked heading's
    candidates, a block at a time) and the numpy reference agree."""
    ranges = _scan(np.random.default_rng(seed), len(angles))
    got = free_heading(heading, ranges, angles, P)
    want = free_heading_reference(heading, ranges, angles, P)
    assert got == want and math.copysign(1.0, got) == math.copysign(1.0, want)
    d = angles - heading
    assert BLOCKED(ranges, np.cos(d), np.sin(d), P.lookahead_m, P.halfwidth_m) == blocked_ref(
        heading, ranges, angles
    )


def blocked_ref(heading: float, ranges: np.ndarray, angles: np.ndarray) -> bool:
    """The reference's first test (no return counts as range 0)."""
    r = np.where(np.isfinite(ranges) & (ranges > 0), ranges, 0.0)
    d = angles - heading
    along, lateral = r * np.cos(d), np.abs(r * np.sin(d))
    return bool(((along > 0) & (along < P.lookahead_m) & (lateral < P.halfwidth_m)).any())
