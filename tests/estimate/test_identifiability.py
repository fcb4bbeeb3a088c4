"""Identifiability: the prior itself has ratio 1; the ratio is a variance ratio (scales, ignores Σw)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.estimate.identifiability import THRESHOLD, identifiable, tangent_basis, variance_ratio
from lfdfuse.estimate.model import FusionModel, prior_tangent_variance, sample_prior

sizes = st.integers(min_value=2, max_value=9)
alphas = st.floats(min_value=0.05, max_value=5.0)


@given(sizes)
def test_tangent_basis_is_orthonormal_and_keeps_the_sum(n: int) -> None:
    b = tangent_basis(n)
    assert b.shape == (n, n - 1)
    np.testing.assert_allclose(b.T @ b, np.eye(n - 1), atol=1e-12)
    np.testing.assert_allclose(np.ones(n) @ b, 0.0, atol=1e-12)


@given(sizes, alphas)
def test_the_prior_covariance_has_ratio_one(n: int, alpha: float) -> None:
    model = FusionModel(alpha=alpha)
    c = prior_tangent_variance(n, model)
    cov = c * (np.eye(n) - np.ones((n, n)) / n)
    assert np.isclose(variance_ratio(cov, model), 1.0)
    assert not identifiable(cov, model)


@given(sizes, st.floats(min_value=1e-4, max_value=10.0), st.integers(0, 2**32 - 1))
def test_ratio_scales_with_the_covariance_and_ignores_the_sum_direction(n: int, s: float, seed: int) -> None:
    model = FusionModel()
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n))
    cov = a @ a.T / n
    r = variance_ratio(cov, model)
    assert r >= 0.0
    assert np.isclose(variance_ratio(s * cov, model), s * r)
    # spread along Σw (which the simplex forbids anyway) changes nothing
    ones = np.ones((n, 1)) / np.sqrt(n)
    assert np.isclose(variance_ratio(cov + 7.0 * ones @ ones.T, model), r)
    assert identifiable(cov, model, threshold=r * 1.01 + 1e-12) and not identifiable(cov, model, threshold=r)


@settings(max_examples=10, deadline=None)
@given(st.integers(2, 5), st.integers(0, 2**32 - 1))
def test_prior_samples_have_ratio_near_one(n: int, seed: int) -> None:
    """Weights drawn from the prior are, by construction, not pinned by any data."""
    model = FusionModel()
    w = np.exp(sample_prior((20_000,), np.ones(n, bool), model, np.random.default_rng(seed)))
    r = variance_ratio(np.cov(w.T), model)
    assert 0.9 < r < 1.1
    assert r > THRESHOLD


def test_one_behaviour_is_always_identifiable() -> None:
    assert variance_ratio(np.array([[0.3]]), FusionModel()) == 0.0
