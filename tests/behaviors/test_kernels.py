"""The compiled per-scan loops (:mod:`lfdfuse.behaviors.kernels`) against their numpy references.

Bit for bit: the behaviour outputs of the fused laser and sonar primitives, the opening flags,
the way ahead and the corridor test, over random scans of several scanner layouts (a 360° + 1
scanner, beam counts around numpy's pairwise-sum block), with returns missing, at max range
and NaN. And the live law holds compiled too: a log computed scan by scan equals it computed whole.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.behaviors import kernels
from lfdfuse.behaviors.openings import (
    OpeningParams,
    ahead_range,
    ahead_range_reference,
    sensed_onsets,
    side_openings,
    side_openings_reference,
)
from lfdfuse.behaviors.primitives import BehaviorState, Observations, compute, resolve_behaviors
from lfdfuse.kernels import jit
from lfdfuse.robot.readings import ScanGeometry

needs_numba = pytest.mark.skipif(
    not (kernels.POOL.ready() and kernels.SIDE_OPEN.ready()), reason="numba kernels unavailable here"
)

LAYOUTS = (
    ScanGeometry(-math.pi / 2, math.pi / 180, 181, 8.0),  # the simulated laser
    ScanGeometry(-math.pi, math.pi / 180, 361, 5.0),  # a Neato: the first bearing twice
    ScanGeometry(-2.0, 4.0 / 126, 127, 10.0),  # one pairwise block
    ScanGeometry(-2.35, 4.7 / 720, 721, 30.0),  # split twice
    ScanGeometry(-0.5, 0.1, 11, 4.0),
)
TARGETS = ("red", "green", "blue")


def _scans(rng: np.random.Generator, n: int, g: ScanGeometry) -> np.ndarray:
    r = rng.uniform(0.05, g.max_range_m * 1.1, (n, g.count))
    near = rng.uniform(size=r.shape) < 0.5
    r[near] = rng.uniform(0.05, 2.5, near.sum())  # many returns within d_max
    for value, share in ((np.inf, 0.1), (np.nan, 0.03), (g.max_range_m, 0.05), (0.0, 0.02), (-1.0, 0.01)):
        r[rng.uniform(size=r.shape) < share] = value
    return r


def _observations(seed: int, n: int, layout: int, sonar: bool) -> Observations:
    rng = np.random.default_rng(seed)
    g = LAYOUTS[layout]
    son = rng.uniform(-0.1, 1.6, (n, 5)) if sonar else None
    if son is not None:
        son[rng.uniform(size=son.shape) < 0.1] = np.inf
    bearing = rng.uniform(-math.pi, math.pi, (n, len(TARGETS)))
    bearing[rng.uniform(size=bearing.shape) < 0.4] = np.nan
    rng_m = rng.uniform(0.0, 3.0, (n, len(TARGETS)))
    return Observations(
        _scans(rng, n, g),
        g,
        son,
        np.linspace(2.4, 3.9, 5) if sonar else None,
        1.5,
        TARGETS,
        bearing,
        rng_m,
    )


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal bit for bit (a zero's sign included)."""
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@needs_numba
@settings(max_examples=80, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 40),
    st.integers(0, len(LAYOUTS) - 1),
    st.booleans(),
    st.sampled_from(["full", "scenario1", "scenario3", "avoid,wall_attract_left,attract_green"]),
)
def test_compiled_primitives_equal_the_numpy_ones(
    seed: int, n: int, layout: int, sonar: bool, preset: str
) -> None:
    obs = _observations(seed, n, layout, sonar)
    names = resolve_behaviors(preset, TARGETS)
    got = compute(obs, names)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(jit.MODE, "numpy")
        want = compute(obs, names)
    assert _same(got.vectors, want.vectors)
    assert _same(got.applicable, want.applicable)
    assert _same(got.goal_met, want.goal_met)
    state = BehaviorState(names)  # live: one scan at a time
    live = [compute(obs.rows(i, i + 1), names, state=state).vectors for i in range(n)]
    assert _same(np.concatenate(live), got.vectors)


@needs_numba
def test_all_zero_pulls_keep_numpy_zero_signs() -> None:
    """Nothing near and every open beam on one side: sums of signed zeros, as numpy adds them."""
    g = LAYOUTS[0]
    r = np.full((3, g.count), 7.5)
    r[1, :] = np.inf
    r[2, g.count // 2 :] = 0.5
    obs = Observations(r, g, None, None, math.inf, (), np.zeros((3, 0)), np.zeros((3, 0)))
    names = resolve_behaviors("full", ())
    got = compute(obs, names)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(jit.MODE, "numpy")
        want = compute(obs, names)
    assert _same(got.vectors, want.vectors)


@needs_numba
@settings(max_examples=80, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 30),
    st.integers(0, len(LAYOUTS) - 1),
    st.floats(-4.0, 4.0),
)
def test_compiled_openings_equal_the_references(seed: int, n: int, layout: int, offset: float) -> None:
    rng = np.random.default_rng(seed)
    g = LAYOUTS[layout]
    r = _scans(rng, n, g)
    r[rng.uniform(size=r.shape) < 0.3] = np.inf  # openings
    params = OpeningParams()
    offsets = rng.uniform(-4.0, 4.0, n)
    assert _same(side_openings(r, g, params), side_openings_reference(r, g, params))
    assert _same(
        side_openings(r, g, params, offset_rad=offsets),
        side_openings_reference(r, g, params, offset_rad=offsets),
    )
    for row in r[:5]:
        for off in (0.0, offset):
            got = ahead_range(row, g, params, offset_rad=off)
            assert got == ahead_range_reference(row, g, params, offset_rad=off)


@needs_numba
@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, len(LAYOUTS) - 1))
def test_compiled_opening_sensor_equals_the_numpy_one(seed: int, layout: int) -> None:
    """A drive through corridors and rooms: the same onsets and held headings tick by tick."""
    rng = np.random.default_rng(seed)
    g = LAYOUTS[layout]
    n = 300
    r = np.full((n, g.count), 1.2) + rng.normal(0.0, 0.05, (n, g.count))
    for start in rng.integers(0, n - 20, 8):  # junctions and rooms
        cols = rng.integers(0, g.count, 2)
        r[start : start + rng.integers(3, 20), min(cols) : max(cols) + 1] = rng.choice([np.inf, 6.0, 2.5])
    step = rng.uniform(0.0, 0.1, n)
    turn = rng.normal(0.0, 0.08, n)
    turn[rng.uniform(size=n) < 0.05] = 0.6  # turning on the spot
    got = sensed_onsets(r, g, step, turn)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(jit.MODE, "numpy")
        want = sensed_onsets(r, g, step, turn)
    assert _same(got[0], want[0]) and _same(got[1], want[1])
