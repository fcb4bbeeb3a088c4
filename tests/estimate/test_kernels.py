"""The particle filter's compiled likelihood loop against its numpy reference.

``sum_cos`` (the sufficient statistic of every particle's likelihood, what the sampler spends
its time in) runs compiled where numba does; :func:`~lfdfuse.estimate.model.sum_cos_reference`
is the numpy it must agree with, on the same inputs, to 1e-12.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.estimate import model
from lfdfuse.estimate.model import RowData, sum_cos, sum_cos_reference

needs_numba = pytest.mark.skipif(not model.SUM_COS.ready(), reason="numba kernels unavailable here")


def _row(rng: np.random.Generator, steps: int, n: int, zeros: bool) -> tuple[RowData, np.ndarray]:
    vectors = rng.normal(0.0, 0.6, (steps, n, 2))
    if zeros:  # behaviours that were not applicable: zero vectors, and zero fused vectors
        vectors[rng.uniform(size=(steps, n)) < 0.3] = 0.0
    demo = rng.normal(0.0, 1.0, (steps, 2))
    return model.row_data(vectors, demo), rng.dirichlet(np.full(n, 0.5), 1)[0]


@needs_numba
@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 400),
    st.integers(1, 9),
    st.integers(1, 300),
    st.booleans(),
)
def test_compiled_sum_cos_agrees_with_the_reference(
    seed: int, steps: int, n: int, particles: int, zeros: bool
) -> None:
    rng = np.random.default_rng(seed)
    data, _ = _row(rng, steps, n, zeros)
    w = rng.dirichlet(np.full(n, 0.5), particles)
    if zeros:
        w[: particles // 3] = 0.0  # an all-zero weight vector: every fused vector is zero
    got, want = sum_cos(data, w), sum_cos_reference(data, w)
    assert got.shape == want.shape == (particles,)
    np.testing.assert_allclose(got, want, rtol=0.0, atol=1e-12)


@needs_numba
def test_compiled_sum_cos_sums_blocks_as_the_reference(monkeypatch: pytest.MonkeyPatch) -> None:
    """Rows longer than one block of steps (the block shrinks with the particle count)."""
    monkeypatch.setattr(model, "BLOCK_ELEMENTS", 64 * 50)
    rng = np.random.default_rng(7)
    data, _ = _row(rng, 1234, 6, True)
    w = rng.dirichlet(np.full(6, 0.5), 50)
    np.testing.assert_allclose(sum_cos(data, w), sum_cos_reference(data, w), rtol=0.0, atol=1e-12)


def test_numpy_mode_runs_the_reference(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LFDFUSE_KERNELS", "numpy")
    rng = np.random.default_rng(3)
    data, _ = _row(rng, 50, 4, False)
    w = rng.dirichlet(np.full(4, 0.5), 20)
    assert np.array_equal(sum_cos(data, w), sum_cos_reference(data, w))


def test_the_loop_itself_is_the_reference_in_plain_python() -> None:
    """The loop numba compiles, run by the interpreter: the same statistic."""
    rng = np.random.default_rng(5)
    data, _ = _row(rng, 40, 3, True)
    w = rng.dirichlet(np.full(3, 0.5), 7)
    wt = np.ascontiguousarray(w.T)
    got = model._sum_cos_loop(data.along, data.across, wt, 16)
    np.testing.assert_allclose(got, sum_cos_reference(data, w), rtol=0.0, atol=1e-12)


@needs_numba
@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-5000.0, 5000.0, allow_nan=False), min_size=1, max_size=50),
    st.integers(1, 6000),
    st.floats(0.05, 5.0),
    st.floats(20.0, 90.0),
    st.integers(2, 40),
)
def test_compiled_log_marginal_agrees_with_the_reference(
    stat: list[float], steps: int, sigma_min: float, sigma_max: float, points: int
) -> None:
    """``log p(data | w)`` from ``S``, κ integrated out: compiled against numpy's log-sum-exp."""
    m = model.FusionModel(sigma_min_deg=sigma_min, sigma_max_deg=sigma_max, kappa_points=points)
    s = np.clip(np.asarray(stat), -steps, steps)  # |S| ≤ T: a sum of cosines
    assert model.LOG_MARGINAL.ready()
    got = model.LOG_MARGINAL(s, float(steps), m.kappas, m._log_norm)
    want = model.log_marginal(s, steps, m)
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-12)


def test_the_row_likelihood_is_the_reference_in_both_modes(monkeypatch: pytest.MonkeyPatch) -> None:
    """``row_loglik`` of a continuous row, compiled and with the numpy references."""
    rng = np.random.default_rng(11)
    data, _ = _row(rng, 300, 5, True)
    w = rng.dirichlet(np.full(5, 0.5), 64)
    m = model.FusionModel()
    fast = model.row_loglik(data, w, m)
    monkeypatch.setenv("LFDFUSE_KERNELS", "numpy")
    ref = model.row_loglik(data, w, m)
    assert np.array_equal(ref, model.log_marginal(sum_cos_reference(data, w), data.steps, m))
    np.testing.assert_allclose(fast, ref, rtol=1e-13, atol=1e-12)
