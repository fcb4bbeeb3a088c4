"""The lag diagnostic's fit: zero error when the demo is a non-negative fusion, invariant under the frame."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.segment.lag import CANDIDATE_LAGS_S, fit_error_deg


def _row(rng: np.random.Generator, n: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    vectors = rng.normal(size=(n, k, 2))
    return vectors, np.full(n, (1 << k) - 1, dtype=np.int64)


@settings(deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 4))
def test_an_exact_non_negative_fusion_fits_with_zero_error(seed: int, k: int) -> None:
    rng = np.random.default_rng(seed)
    vectors, bac = _row(rng, 30, k)
    w = rng.uniform(0.1, 1.0, k)
    demo = np.einsum("tnc,n->tc", vectors, w)
    err, steps = fit_error_deg(vectors, demo, bac)
    assert steps == 30
    assert err < 1e-4


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(-math.pi, math.pi), st.floats(0.1, 10.0))
def test_error_is_invariant_under_rotation_and_scale(seed: int, angle: float, scale: float) -> None:
    rng = np.random.default_rng(seed)
    vectors, bac = _row(rng, 25, 2)
    demo = rng.normal(size=(25, 2))
    rot = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    err, n = fit_error_deg(vectors, demo, bac)
    err2, n2 = fit_error_deg(vectors @ rot.T, scale * demo @ rot.T, bac)
    assert n == n2 == 25
    assert 0.0 <= err <= 180.0
    assert math.isclose(err, err2, rel_tol=1e-6, abs_tol=1e-6)


def test_groups_without_behaviours_or_with_one_step_enter_no_fit() -> None:
    rng = np.random.default_rng(0)
    vectors = rng.normal(size=(3, 2, 2))
    err, n = fit_error_deg(vectors, rng.normal(size=(3, 2)), np.array([0, 0, 1]))
    assert math.isnan(err) and n == 0


def test_candidate_lags_are_sorted_tenths_from_zero_to_one_second() -> None:
    assert CANDIDATE_LAGS_S[0] == 0.0 and CANDIDATE_LAGS_S[-1] == 1.0
    assert list(CANDIDATE_LAGS_S) == sorted(set(CANDIDATE_LAGS_S))


def test_a_fit_that_collapses_to_zero_counts_as_a_right_angle() -> None:
    """Demo opposite to the only behaviour: nnls gives w = 0, whose heading is undefined (90°, not 0 or 180)."""
    vectors = np.tile(np.array([[[1.0, 0.0]]]), (4, 1, 1))
    demo = np.tile(np.array([[-1.0, 0.0]]), (4, 1))
    for sign in (1.0, -1.0):  # the sign of the zeros must not matter
        err, n = fit_error_deg(sign * vectors, sign * demo, np.ones(4, dtype=np.int64))
        assert n == 4 and math.isclose(err, 90.0)
