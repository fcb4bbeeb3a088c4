"""The particle filter's compiled likelihood loop against its numpy reference.

``sum_cos`` (the sufficient statistic of every particle's likelihood, what the sampler spends
its time in) runs compiled where numba does; :func:`~lfdfuse.estimate.model.sum_cos_reference`
is the numpy it must agree with, on the same inputs, to 1e-12.
"""

from __future__ import annotations

import math
import platform

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.estimate import discrete_kernels, kernels, model, smc, smc_kernels
from lfdfuse.estimate.model import RowData, sum_cos, sum_cos_reference

needs_numba = pytest.mark.skipif(not kernels.SUM_COS.ready(), reason="numba kernels unavailable here")


def _row(rng: np.random.Generator, steps: int, n: int, zeros: bool) -> tuple[RowData, np.ndarray]:
    vectors = rng.normal(0.0, 0.6, (steps, n, 2))
    if zeros:  # behaviours that were not applicable: zero vectors, and zero fused vectors
        vectors[rng.uniform(size=(steps, n)) < 0.3] = 0.0
    demo = rng.normal(0.0, 1.0, (steps, 2))
    return model.row_data(vectors, demo), rng.dirichlet(np.full(n, 0.5), 1)[0]


def _fused_rows(rng: np.random.Generator, shapes: tuple[tuple[int, int], ...]) -> list[model.Row]:
    """Continuous rows of ``(behaviours, steps)`` each: a noisy fusion of random vectors."""
    rows: list[model.Row] = []
    for n, t in shapes:
        vectors = rng.normal(0.0, 0.6, (t, n, 2))
        w = rng.dirichlet(np.full(n, 0.5))
        demo = np.einsum("tnk,n->tk", vectors, w) + rng.normal(0.0, 0.1, (t, 2))
        rows.append(model.row_data(vectors, demo))
    return rows


def _sampler_pass(rows: list[model.Row], *, trials: int, particles: int, seed: int) -> smc.SMCResult:
    """One whole pass of the sampler over ``rows``."""
    return smc.TemperedSMC(
        rows,
        trials=trials,
        model=model.FusionModel(),
        params=smc.SMCParams(particles=particles),
        rng=np.random.default_rng(seed),
    ).run()


class _NotCompiled:
    """A kernel that never compiles: its caller runs the numpy reference."""

    def ready(self) -> bool:
        return False


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
    monkeypatch.setattr(kernels, "BLOCK_ELEMENTS", 64 * 50)
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
    got = kernels._sum_cos_loop(data.along, data.across, wt, 16, kernels.behaviour_width(3))
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
    assert kernels.LOG_MARGINAL.ready()
    got = kernels.LOG_MARGINAL(s, float(steps), m.kappas, m._log_norm)
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


@needs_numba
@pytest.mark.parametrize("seed", range(3))
def test_the_sampler_skipping_finished_trials_gives_the_same_draws(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With the compiled likelihood a row's finished trials are not computed again: every draw,
    evidence and acceptance is the one computing them all gives, to the bit."""
    rows = _fused_rows(np.random.default_rng(seed), ((3, 80), (5, 200), (2, 30)))
    skipped: list[int] = []
    real = smc._Rows.loglik

    def counting(
        self: smc._Rows, w: np.ndarray, active: np.ndarray, chains: np.ndarray | None = None
    ) -> np.ndarray:
        if chains is not None:
            skipped.append(int((~chains[active]).sum()))
        return real(self, w, active, chains)

    monkeypatch.setattr(smc._Rows, "loglik", counting)
    fast = _sampler_pass(rows, trials=5, particles=64, seed=seed)
    monkeypatch.setattr(smc, "subset_exact", lambda _data: False)
    whole = _sampler_pass(rows, trials=5, particles=64, seed=seed)
    assert sum(skipped) > 0  # some trials finished before others: the subset path ran
    for a, b in zip(
        (fast.logw, fast.log_evidence, fast.acceptance),
        (whole.logw, whole.log_evidence, whole.acceptance),
        strict=True,
    ):
        assert np.array_equal(a, b)
    assert fast.iterations == whole.iterations


@needs_numba
@settings(max_examples=150, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 40),
    st.sampled_from([1, 2, 5, 6, 7, 8, 9, 13, 64, 128, 129, 384, 1000]),
    st.sampled_from([0.1, 1.0, 30.0, 1000.0]),
    st.integers(0, 4),
    st.booleans(),
)
def test_compiled_logsumexp_is_scipys(
    seed: int, rows: int, length: int, scale: float, special: int, keepdims: bool
) -> None:
    """Bit for bit where numpy's exp and log are libm's, ties, infinities and NaN included (the
    sampler's path through it is chaotic: one ulp there is another posterior draw), and within an
    ulp or two where numpy takes a SIMD path of its own."""
    from scipy.special import logsumexp

    rng = np.random.default_rng(seed)
    a = rng.normal(0.0, scale, (rows, length))
    if special == 1:  # masked behaviours
        a[rng.uniform(size=a.shape) < 0.3] = -np.inf
    elif special == 2:
        a[0] = -np.inf
    elif special == 3:  # ties at the maximum
        a[:, length // 2] = a[:, 0] = a.max()
    elif special == 4:
        a[rng.uniform(size=a.shape) < 0.05] = np.inf
        a[rng.uniform(size=a.shape) < 0.02] = np.nan
    with np.errstate(all="ignore"):
        want = logsumexp(a, axis=-1, keepdims=keepdims)
    got = kernels.logsumexp_last(a, keepdims=keepdims)
    a3 = a.reshape(rows, 1, length)
    got3 = kernels.logsumexp_last(a3, keepdims=True)
    with np.errstate(all="ignore"):
        want3 = logsumexp(a3, axis=2, keepdims=True)
    assert got.shape == want.shape and got3.shape == want3.shape
    if _libm_elementwise():
        assert got.tobytes() == want.tobytes() and got3.tobytes() == want3.tobytes()
    else:  # numpy's own SIMD exp and log (AVX-512): an ulp apart, the same infinities and NaN
        np.testing.assert_allclose(got, want, rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(got3, want3, rtol=1e-14, atol=1e-14)


@needs_numba
@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 5000), st.integers(1, 120))
def test_compiled_log_marginal_skips_only_exact_zeros(seed: int, steps: int, particles: int) -> None:
    """Nodes far below the peak add +0.0: the compiled loop skips their exp and gives the bits
    of the loop that adds every node."""
    rng = np.random.default_rng(seed)
    m = model.FusionModel()
    s = steps - np.abs(rng.normal(0.0, 0.2 * steps, particles))
    s[rng.uniform(size=particles) < 0.05] = steps  # a perfect fit
    got = kernels.LOG_MARGINAL(s, float(steps), m.kappas, m._log_norm)
    want = np.empty(particles)
    for p in range(particles):  # every node's exp, in order
        terms = [
            float(k) * (s[p] - steps) - steps * float(c) for k, c in zip(m.kappas, m._log_norm, strict=True)
        ]
        top = max(terms)
        acc = 0.0
        for x in terms:
            acc += math.exp(x - top)
        want[p] = top + math.log(acc) - math.log(len(terms))
    assert got.tobytes() == want.tobytes()
    np.testing.assert_allclose(got, model.log_marginal(s, steps, m), rtol=0.0, atol=1e-12)


def _particles(
    rng: np.random.Generator, chains: int, m: int, n: int, padded: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Log-weights ``(C, M, n)`` of Dirichlet particles and the behaviours' mask ``(C, n)`` (rows of
    fewer behaviours padded with −inf, as the sampler pads them)."""
    sizes = rng.integers(1 if padded else n, n + 1, chains)
    mask = np.arange(n)[None, :] < sizes[:, None]
    logw = np.full((chains, m, n), -np.inf)
    for c in range(chains):
        k = int(sizes[c])
        logw[c, :, :k] = np.log(np.maximum(rng.dirichlet(np.full(k, 0.5), m), 1e-300))
    return logw, mask


@needs_numba
@settings(max_examples=80, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 6),
    st.sampled_from([1, 2, 3, 17, 64, 384]),
    st.integers(1, 20),
    st.booleans(),
)
def test_compiled_move_agrees_with_the_reference(
    seed: int, chains: int, m: int, n: int, padded: bool
) -> None:
    """A Metropolis move's frame (reference behaviour, log-ratio coordinates, covariance) and
    proposal (log-weights and log priors) against the numpy steps they replace: to 1e-12, and on
    x86-64 (the reductions' order known) to the bit."""
    assert smc_kernels.MOVE_FRAME.ready() and smc_kernels.MOVE_PROPOSE.ready()
    rng = np.random.default_rng(seed)
    logw, mask = _particles(rng, chains, m, n, padded)
    active = np.ones(chains, dtype=bool)
    ref, y, cov = smc_kernels.MOVE_FRAME(logw, mask, active)
    want_ref, want_y, want_cov = smc_kernels.move_frame_reference(logw, mask)
    assert np.array_equal(ref, want_ref)
    np.testing.assert_allclose(y, want_y, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(cov, want_cov, rtol=1e-12, atol=1e-12)
    chol = np.linalg.cholesky(want_cov)
    z = rng.standard_normal(logw.shape)
    scale = rng.uniform(0.05, 3.0, chains)
    got = smc_kernels.MOVE_PROPOSE(want_y, logw, mask, want_ref, chol, z, scale, 0.5, active)
    want = smc_kernels.move_propose_reference(want_y, logw, mask, want_ref, chol, z, scale, 0.5)
    for g, w in zip(got, want, strict=True):
        assert g.shape == w.shape
        np.testing.assert_allclose(g, w, rtol=1e-12, atol=1e-12)
    if platform.machine() in ("x86_64", "AMD64"):
        assert y.tobytes() == want_y.tobytes() and cov.tobytes() == want_cov.tobytes()
        assert all(g.tobytes() == w.tobytes() for g, w in zip(got, want, strict=True))


@needs_numba
def test_the_compiled_move_leaves_inactive_chains_as_they_are() -> None:
    """A frozen chain's particles are not proposed: its log-weights come back unchanged and its
    prior equal before and after (the sampler accepts nothing there)."""
    rng = np.random.default_rng(2)
    logw, mask = _particles(rng, 4, 32, 5, True)
    active = np.array([True, False, True, False])
    ref, y, cov = smc_kernels.MOVE_FRAME(logw, mask, active)
    chol = np.linalg.cholesky(cov)
    z = rng.standard_normal(logw.shape)
    logw_new, prior, prior_new = smc_kernels.MOVE_PROPOSE(
        y, logw, mask, ref, chol, z, np.ones(4), 0.5, active
    )
    assert np.array_equal(logw_new[~active], logw[~active])
    assert np.array_equal(prior[~active], prior_new[~active])
    assert not np.array_equal(logw_new[active], logw[active])
    want = smc_kernels.move_propose_reference(y, logw, mask, ref, chol, z, np.ones(4), 0.5)
    np.testing.assert_allclose(logw_new[active], want[0][active], rtol=0.0, atol=1e-12)


@needs_numba
def test_the_sampler_with_compiled_moves_gives_the_reference_draws(monkeypatch: pytest.MonkeyPatch) -> None:
    """A whole pass (rows of 2 to 12 behaviours, padded, trials finishing apart) with the compiled
    moves and with the numpy ones: the same draws, to the bit on x86-64."""
    rows = _fused_rows(np.random.default_rng(4), ((3, 80), (5, 200), (2, 30), (9, 50), (12, 40)))
    fast = _sampler_pass(rows, trials=3, particles=48, seed=5)
    monkeypatch.setattr(smc, "MOVE_FRAME", _NotCompiled())  # the numpy moves, the same likelihood
    ref = _sampler_pass(rows, trials=3, particles=48, seed=5)
    assert fast.iterations == ref.iterations
    np.testing.assert_allclose(np.exp(fast.logw), np.exp(ref.logw), rtol=0.0, atol=1e-9)
    if platform.machine() in ("x86_64", "AMD64"):
        assert fast.logw.tobytes() == ref.logw.tobytes()
        assert fast.log_evidence.tobytes() == ref.log_evidence.tobytes()


@needs_numba
@settings(max_examples=25, deadline=None)
@given(
    st.integers(0, 2**32 - 1), st.integers(1, 300), st.integers(1, 8), st.integers(1, 700), st.integers(2, 5)
)
def test_a_rows_likelihood_shared_over_threads_is_the_same_bits(
    seed: int, steps: int, n: int, particles: int, cores: int
) -> None:
    """The particles of a long row are shared out over the cores: every particle's likelihood is
    the bits one thread gives it (and the numpy reference's to 1e-12), whatever the split."""
    rng = np.random.default_rng(seed)
    data, _ = _row(rng, steps, n, True)
    w = rng.dirichlet(np.full(n, 0.5), particles)
    m = model.FusionModel()
    one = model.row_loglik(data, w, m)  # compiles this width: the split needs it warm
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(kernels, "SPLIT_WORK", 1)
        patch.setattr(kernels, "_cores", lambda: cores)
        shared = model.row_loglik(data, w, m)
    assert shared.tobytes() == one.tobytes()
    want = model.log_marginal(sum_cos_reference(data, w), data.steps, m)
    np.testing.assert_allclose(shared, want, rtol=1e-13, atol=1e-12)


@needs_numba
@settings(max_examples=80, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 6),
    st.sampled_from([1, 2, 3, 5, 17, 64, 129, 384, 1000, 1536]),
    st.floats(0.0, 4.0),
    st.sampled_from([0.3, 0.5, 0.9]),
)
def test_compiled_tempering_step_agrees_with_the_reference(
    seed: int, chains: int, m: int, spread: float, share: float
) -> None:
    """The adaptive temperature step (the ESS bisection) against numpy's: to 1e-12, and on x86-64
    (numpy's sums' order known) to the bit — a step decides every later draw."""
    assert smc_kernels.NEXT_DELTA.ready()
    rng = np.random.default_rng(seed)
    ll = rng.normal(0.0, 10.0**spread, (chains, m)) - rng.uniform(0.0, 1e4, (chains, 1))
    room = rng.uniform(0.0, 1.0, chains) * (rng.uniform(size=chains) < 0.8)  # some chains done
    got = smc_kernels.NEXT_DELTA(ll, room, share * m)
    want = smc_kernels.next_delta_reference(ll, room, share * m)
    np.testing.assert_allclose(got, want, rtol=0.0, atol=1e-12)
    assert np.all((got >= 0.0) & (got <= room))
    if platform.machine() in ("x86_64", "AMD64"):
        assert got.tobytes() == want.tobytes()


def _libm_elementwise() -> bool:
    """Whether numpy's exp, log, arctan2 and hypot of float64 give libm's bits here (they do
    unless a build takes a SIMD path of its own, as numpy's AVX-512 exp and log do): the compiled
    loops call libm, so they give the reference's bits where they are the same functions."""
    rng = np.random.default_rng(0)
    x = rng.uniform(1e-6, 1.0, 4096)
    a, b = rng.normal(0.0, 1.0, (2, 4096))
    logs = np.array([math.log(v) for v in x])
    angles = np.array([math.atan2(v, u) for u, v in zip(a, b, strict=True)])
    norms = np.array([math.hypot(u, v) for u, v in zip(a, b, strict=True)])
    return bool(
        np.array_equal(np.log(x), logs)
        and np.array_equal(np.exp(-30.0 * x), np.array([math.exp(-30.0 * v) for v in x]))
        and np.array_equal(np.arctan2(b, a), angles)
        and np.array_equal(np.hypot(a, b), norms)
    )


def _decisions(
    rng: np.random.Generator, steps: int, n: int, zeros: bool, sizes: str, wide: float
) -> model.DiscreteRowData:
    """A discrete row: the behaviours' vectors (some zero with ``zeros``), each decision's
    interval anywhere on the circle (wrapping past ±π where it does; a ``wide`` share the full
    turn, −π to π), out of one command set (``sizes="one"``) or pooled sets of several sizes."""
    vx, vy = rng.normal(0.0, 0.6, (2, steps, n))
    if zeros:
        gone = rng.uniform(size=(steps, n)) < 0.3
        vx[gone] = vy[gone] = 0.0
    lo = rng.uniform(-math.pi, math.pi, steps)
    hi = lo + rng.uniform(1e-3, 2.0 * math.pi - 1e-3, steps)
    full = rng.uniform(size=steps) < wide
    lo[full], hi[full] = -math.pi, math.pi
    commands: int | np.ndarray = int(rng.integers(1, 9))
    if sizes == "pooled":
        commands = rng.choice([3.0, 5.0, 7.0], steps)
    return model.DiscreteRowData(vx, vy, lo, hi, commands)


needs_discrete = pytest.mark.skipif(
    not discrete_kernels.DISCRETE_BLOCK.ready(), reason="numba kernels unavailable here"
)


@needs_discrete
@settings(max_examples=80, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 700),
    st.integers(1, 9),
    st.sampled_from([1, 2, 3, 17, 64, 200, 384]),
    st.booleans(),
    st.sampled_from(["one", "pooled"]),
    st.sampled_from([0.0, 0.02, 0.2, 1.0]),
    st.sampled_from([0.0, 0.1, 1.0]),
    st.sampled_from([4, 16, 33]),
)
def test_compiled_discrete_likelihood_is_the_reference(
    seed: int,
    steps: int,
    n: int,
    particles: int,
    zeros: bool,
    sizes: str,
    lapse: float,
    wide: float,
    nodes: int,
) -> None:
    """``log p(c₁…c_T | w)`` of the discrete command model, compiled and in numpy, over rows of
    many blocks (the block shrinks with particles × nodes), zero vectors and zero weights, every
    lapse (none: log 0 is −∞ in both): to the bit where numpy's elementwise functions are libm's,
    and to 1e-12 everywhere (relative, or absolute where the log-likelihood is near 0)."""
    rng = np.random.default_rng(seed)
    data = _decisions(rng, steps, n, zeros, sizes, wide)
    w = rng.dirichlet(np.full(n, 0.5), particles)
    if zeros:
        w[: particles // 3] = 0.0  # every fused vector zero: the interval's width over 2π
    m = model.FusionModel(lapse=lapse, discrete_kappa_points=nodes)
    got = model.discrete_log_marginal(data, w, m)
    with np.errstate(divide="ignore"):
        want = model.discrete_log_marginal_reference(data, w, m)
    assert got.shape == want.shape == (particles,)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
    if _libm_elementwise():
        assert got.tobytes() == want.tobytes()


@needs_discrete
@settings(max_examples=25, deadline=None)
@given(
    st.integers(0, 2**32 - 1), st.integers(1, 300), st.integers(1, 8), st.integers(1, 700), st.integers(2, 5)
)
def test_a_discrete_rows_likelihood_shared_over_threads_is_the_same_bits(
    seed: int, steps: int, n: int, particles: int, cores: int
) -> None:
    """The particles of a large block are shared out over the cores: every particle's bits are
    the ones a single thread gives it."""
    rng = np.random.default_rng(seed)
    data = _decisions(rng, steps, n, True, "pooled", 0.1)
    w = rng.dirichlet(np.full(n, 0.5), particles)
    m = model.FusionModel()
    one = model.discrete_log_marginal(data, w, m)  # compiles: the split needs the loop warm
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(kernels, "SPLIT_WORK", 1)
        patch.setattr(kernels, "_cores", lambda: cores)
        shared = model.discrete_log_marginal(data, w, m)
    assert shared.tobytes() == one.tobytes()
    np.testing.assert_allclose(
        shared, model.discrete_log_marginal_reference(data, w, m), rtol=1e-12, atol=1e-12
    )


def test_numpy_mode_runs_the_discrete_reference(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LFDFUSE_KERNELS", "numpy")
    rng = np.random.default_rng(8)
    data = _decisions(rng, 60, 4, True, "pooled", 0.1)
    w = rng.dirichlet(np.full(4, 0.5), 30)
    m = model.FusionModel()
    assert not discrete_kernels.DISCRETE_BLOCK.ready()
    got = model.row_loglik(data, w, m)
    assert got.tobytes() == model.discrete_log_marginal_reference(data, w, m).tobytes()
    assert np.all(np.isfinite(got)) and np.all(got < 0.0)


def test_the_discrete_loop_itself_is_the_reference_in_plain_python() -> None:
    """The loop numba compiles, run by the interpreter (Python's math is libm, its float ``%``
    numpy's remainder): the reference's numbers, a particle share at a time."""
    rng = np.random.default_rng(9)
    data = _decisions(rng, 25, 3, True, "one", 0.2)
    w = rng.dirichlet(np.full(3, 0.5), 6)
    w[0] = 0.0
    m = model.FusionModel()
    assert isinstance(data.commands, int)
    a, b = data.vx @ w.T, data.vy @ w.T
    lapse = np.full(data.steps, m.lapse / data.commands)
    ll = np.zeros((6, m.vm_cdf_rows.shape[1]))
    for first, stop in ((0, 2), (2, 6)):
        discrete_kernels._discrete_block_loop(
            a, b, data.lo, data.hi - data.lo, lapse, 1.0 - m.lapse, m.vm_cdf_rows, ll[first:stop], first
        )
    got = kernels.logsumexp_last(ll) - math.log(ll.shape[1])
    want = model.discrete_log_marginal_reference(data, w, m)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
    if _libm_elementwise():
        assert got.tobytes() == want.tobytes()


def test_the_turns_remainder_is_numpys() -> None:
    """The shift of a decision's interval by the fused heading: numpy's remainder by 2π to the
    bit, at the edges of a turn, signed zeros, tiny negatives (that round up to 2π) and beyond."""
    y = 2.0 * math.pi
    rng = np.random.default_rng(12)
    edges = [0.0, -0.0, y, -y, 2 * y, -2 * y, np.nextafter(y, 0.0), np.nextafter(2 * y, 0.0), -1e-300, -1e-17]
    x = np.concatenate([rng.uniform(-3 * y, 3 * y, 20000), edges, [1e-300, 3 * y, 1e6]])
    got = np.array([discrete_kernels._remainder_turn(float(v)) for v in x])
    assert got.tobytes() == np.remainder(x, y).tobytes()


@needs_discrete
def test_the_sampler_with_the_compiled_discrete_likelihood_gives_the_reference_draws(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A whole pass over keyboard rows (one command set, pooled sets of several sizes, and a row
    mixing a scripted demo's steps with a person's decisions) with the compiled discrete
    likelihood and with its numpy reference: the same draws, to the bit where numpy's elementwise
    functions are libm's (a pass is chaotic: one ulp there is another posterior)."""
    rng = np.random.default_rng(6)
    rows: list[model.Row] = [
        _decisions(rng, 120, 4, True, "one", 0.05),
        _decisions(rng, 60, 6, False, "pooled", 0.0),
    ]
    vectors = rng.normal(0.0, 0.6, (50, 3, 2))
    rows.append(
        model.MixedRowData(
            model.row_data(vectors, rng.normal(0.0, 1.0, (50, 2))), _decisions(rng, 40, 3, True, "one", 0.0)
        )
    )

    fast = _sampler_pass(rows, trials=2, particles=96, seed=2)
    monkeypatch.setattr(model, "DISCRETE_BLOCK", _NotCompiled())
    with np.errstate(divide="ignore"):
        ref = _sampler_pass(rows, trials=2, particles=96, seed=2)
    assert fast.iterations == ref.iterations
    np.testing.assert_allclose(np.exp(fast.logw), np.exp(ref.logw), rtol=0.0, atol=1e-9)
    if _libm_elementwise():
        assert fast.logw.tobytes() == ref.logw.tobytes()
        assert fast.log_evidence.tobytes() == ref.log_evidence.tobytes()
