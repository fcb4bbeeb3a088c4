"""Resampling schemes: laws over random log-weights (hypothesis)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from lfdfuse.estimate.resampling import ess, gather, multinomial, normalised, systematic

logweights = arrays(
    np.float64,
    st.tuples(st.integers(1, 4), st.integers(1, 40)),
    elements=st.floats(-30.0, 30.0, allow_nan=False),
)


@settings(max_examples=60, deadline=None)
@given(logweights, st.floats(0.0, 0.999))
def test_systematic_copies_each_particle_floor_or_ceil_of_m_w_times(logw: np.ndarray, u: float) -> None:
    c, m = logw.shape
    idx = systematic(logw, np.full(c, u))
    assert idx.shape == (c, m) and (idx >= 0).all() and (idx < m).all()
    counts = np.stack([np.bincount(row, minlength=m) for row in idx])
    expect = m * normalised(logw)
    assert (counts >= np.floor(expect - 1e-6)).all() and (counts <= np.ceil(expect + 1e-6)).all()


@settings(max_examples=60, deadline=None)
@given(logweights)
def test_ess_lies_between_one_and_m_and_is_m_for_equal_weights(logw: np.ndarray) -> None:
    m = logw.shape[1]
    e = ess(logw)
    assert (e >= 1 - 1e-9).all() and (e <= m + 1e-9).all()
    assert np.allclose(ess(np.zeros_like(logw)), m)


@settings(max_examples=30, deadline=None)
@given(logweights, st.integers(0, 2**32 - 1))
def test_multinomial_picks_only_particles_with_weight(logw: np.ndarray, seed: int) -> None:
    idx = multinomial(logw, np.random.default_rng(seed))
    w = normalised(logw)
    assert (np.take_along_axis(w, idx, axis=1) > 0).all()


def test_gather_keeps_trailing_axes() -> None:
    x = np.arange(2 * 3 * 2).reshape(2, 3, 2)
    out = gather(x, np.array([[2, 2, 0], [1, 0, 0]]))
    assert out.tolist() == [[[4, 5], [4, 5], [0, 1]], [[8, 9], [6, 7], [6, 7]]]
