"""numpy's pairwise sum, written out: the Python model, the loop a kernel calls, and that loop
compiled, each give ``np.add.reduce``'s bits (signs of zero, overflow and NaN included)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.kernels import jit
from lfdfuse.kernels.pairwise import STACK, pairwise_sum, pairwise_sum_reference


def _loop_sum(x: np.ndarray) -> float:
    buf = np.ascontiguousarray(x)
    lo, n, state = (np.empty(STACK, dtype=np.int64) for _ in range(3))
    return pairwise_sum(buf, len(buf), lo, n, state, np.empty(STACK))


def _sums_loop(rows: np.ndarray, out: np.ndarray) -> None:
    lo = np.empty(STACK, dtype=np.int64)
    n = np.empty(STACK, dtype=np.int64)
    state = np.empty(STACK, dtype=np.int64)
    vals = np.empty(STACK)
    buf = np.empty(rows.shape[1])
    for i in range(rows.shape[0]):
        for j in range(rows.shape[1]):
            buf[j] = rows[i, j]
        out[i] = pairwise_sum(buf, rows.shape[1], lo, n, state, vals)


SUMS = jit.kernel(_sums_loop, calls=[pairwise_sum])


def _same(got: float, want: float) -> bool:
    if math.isnan(want):
        return math.isnan(got)
    return got == want and math.copysign(1.0, got) == math.copysign(1.0, want)


def _rows(seed: int, n: int, scale: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(3, n)) * scale * rng.choice([1.0, -1.0, 1e8], size=(3, n))
    x[1] = -0.0 * np.abs(x[1])  # negative zeros: numpy's sum is +0.0
    if n:
        x[2, rng.integers(n)] = rng.choice([np.inf, -np.inf, np.nan])
    return x


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 1100), st.sampled_from([1.0, 1e-300, 1e290, 0.0]))
def test_the_model_and_the_loop_are_numpys(seed: int, n: int, scale: float) -> None:
    for row in _rows(seed, n, scale):
        want = float(np.add.reduce(row))
        assert _same(pairwise_sum_reference(row), want)
        assert _same(_loop_sum(row), want)


@pytest.mark.skipif(not SUMS.ready(), reason="numba is not available here")
@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 1100), st.sampled_from([1.0, 1e-300, 1e290]))
def test_the_compiled_loop_is_numpys(seed: int, n: int, scale: float) -> None:
    rows = _rows(seed, n, scale)
    out = np.empty(len(rows))
    SUMS(rows, out)
    for got, want in zip(out, np.add.reduce(rows, axis=1), strict=True):
        assert _same(float(got), float(want))
