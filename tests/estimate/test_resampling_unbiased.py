"""Resampling is unbiased: each particle is copied ``M wⱼ`` times on average over the uniforms."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from lfdfuse.estimate.resampling import multinomial, normalised, resample, systematic

rows = arrays(np.float64, st.integers(1, 12), elements=st.floats(-20.0, 20.0, allow_nan=False))


def _counts(idx: np.ndarray, m: int) -> np.ndarray:
    """Copies of each particle per chain ``(C, M)``."""
    return (idx[:, :, None] == np.arange(m)[None, None, :]).sum(axis=1)


@settings(max_examples=25, deadline=None)
@given(rows)
def test_systematic_is_exactly_unbiased_over_its_uniform(logw: np.ndarray) -> None:
    """Averaged over a grid of G uniforms (one chain each), counts are M w within 2/G."""
    m, g = len(logw), 4000
    u = (np.arange(g) + 0.5) / g
    idx = systematic(np.tile(logw, (g, 1)), u)
    mean = _counts(idx, m).mean(axis=0)
    np.testing.assert_allclose(mean, m * normalised(logw[None])[0], atol=2.0 / g + 1e-9)


@settings(max_examples=15, deadline=None, derandomize=True)
@given(rows, st.integers(0, 2**32 - 1))
def test_multinomial_and_the_default_are_unbiased_in_expectation(logw: np.ndarray, seed: int) -> None:
    m, chains = len(logw), 3000
    w = normalised(logw[None])[0]
    tiled = np.tile(logw, (chains, 1))
    for draw in (multinomial, resample):
        mean = _counts(draw(tiled, np.random.default_rng(seed)), m).mean(axis=0)
        # a copy count has variance at most M w (1 − w): six standard errors of the mean; for a
        # particle of tiny weight the normal bound fails (a single copy among the chains is then a
        # rare but fair event), so a few copies' worth (3 / chains) is allowed beside it
        sd = np.sqrt(m * w * (1 - w) / chains)
        assert (np.abs(mean - m * w) <= 6 * sd + 3.0 / chains).all()
