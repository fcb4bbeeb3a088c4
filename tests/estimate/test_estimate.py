"""Fusion estimation: the sampler against an exact grid posterior, recovery beside a
least-squares heading fit, identifiability, degenerate groups, the paper's filter, baselines."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lfdfuse.estimate.baselines import angle_errors, arbitration_weights, heading_fit_weights, nnls_weights
from lfdfuse.estimate.model import FusionModel, log_marginal, row_data, sum_cos
from lfdfuse.estimate.paper import PFParams, reference_step, run_filter, step
from lfdfuse.estimate.pipeline import EstimateOptions, estimate_group, estimate_groups
from lfdfuse.estimate.smc import SMCParams, TemperedSMC

NOISE = math.radians(5.0)


def synthetic(
    rng: np.random.Generator, t: int, w: np.ndarray, noise: float = NOISE
) -> tuple[np.ndarray, np.ndarray]:
    """Behaviour vectors with random directions and magnitudes, a heading from ``w`` + noise."""
    n = len(w)
    ang = rng.uniform(-np.pi, np.pi, (t, n))
    mag = rng.uniform(0.2, 1.0, (t, n))
    v = np.stack([mag * np.cos(ang), mag * np.sin(ang)], axis=-1)
    f = np.einsum("tnd,n->td", v, w)
    th = np.arctan2(f[:, 1], f[:, 0]) + rng.normal(0.0, noise, t)
    return v, np.stack([np.cos(th), np.sin(th)], axis=-1)


def sparse_truth(rng: np.random.Generator, n: int) -> np.ndarray:
    """A designer's row: two or three behaviours with clearly different weights, the rest 0."""
    k = int(rng.integers(2, min(n, 3) + 1))
    w = np.zeros(n)
    w[rng.choice(n, k, replace=False)] = rng.dirichlet(np.full(k, 3.0))
    return w


def grid_posterior(v: np.ndarray, vr: np.ndarray, model: FusionModel) -> tuple[np.ndarray, np.ndarray]:
    """Posterior mean and std by brute force on a fine grid of the simplex (n = 2 or 3)."""
    n = v.shape[1]
    a = (np.arange(1200 if n == 2 else 250) + 0.5) / (1200 if n == 2 else 250)
    if n == 2:
        w = np.stack([a, 1 - a], -1)
    else:
        x, y = np.meshgrid(a, a)
        keep = x + y < 1
        w = np.stack([x[keep], y[keep], 1 - x[keep] - y[keep]], -1)
    d = row_data(v, vr)
    lp = log_marginal(sum_cos(d, w), d.steps, model) + (model.alpha - 1) * np.log(w).sum(-1)
    p = np.exp(lp - lp.max())
    p /= p.sum()
    mu = p @ w
    return mu, np.sqrt(p @ (w - mu) ** 2)


@pytest.mark.parametrize(
    ("n", "t", "seed"), [(2, 1, 0), (2, 30, 1), (2, 400, 2), (3, 3, 3), (3, 60, 4), (3, 500, 5)]
)
def test_sampler_matches_the_exact_grid_posterior(n: int, t: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    w = rng.dirichlet(np.ones(n))
    v, vr = synthetic(rng, t, w, math.radians(8.0))
    model = FusionModel()
    mu, sd = grid_posterior(v, vr, model)
    res = TemperedSMC(
        [row_data(v, vr)], trials=4, model=model, params=SMCParams(particles=1000), rng=rng
    ).run()
    mean = res.mean()[:, :n].mean(axis=0)
    std = np.sqrt(np.diagonal(res.cov(), axis1=1, axis2=2)[:, :n]).mean(axis=0)
    assert np.allclose(mean, mu, atol=0.2 * sd.max() + 0.002), (mean, mu, sd)
    assert np.allclose(std, sd, rtol=0.15, atol=0.002), (std, sd)


@pytest.mark.parametrize("n", [2, 3, 5])
def test_without_information_the_posterior_is_the_prior(n: int) -> None:
    """Zero behaviour vectors say nothing: the moves must leave the Dirichlet prior invariant."""
    rng = np.random.default_rng(n)
    model = FusionModel()
    v = np.zeros((40, n, 2))
    vr = np.tile([1.0, 0.0], (40, 1))
    res = TemperedSMC(
        [row_data(v, vr)], trials=4, model=model, params=SMCParams(particles=2000), rng=rng
    ).run()
    a0 = n * model.alpha
    sd = math.sqrt(model.alpha * (a0 - model.alpha) / (a0 * a0 * (a0 + 1)))
    w = res.weights[:, :, :n].reshape(-1, n)
    assert np.allclose(w.mean(axis=0), 1.0 / n, atol=0.03)
    assert np.allclose(w.std(axis=0), sd, rtol=0.1)


@pytest.mark.parametrize("seed", range(6))
def test_where_the_data_pins_a_row_the_estimate_is_as_close_as_a_heading_fit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 7))
    w = sparse_truth(rng, n)
    v, vr = synthetic(rng, int(rng.integers(200, 800)), w)
    est = estimate_group(v, vr, opts=EstimateOptions(seed=seed), rng=rng)
    fit = heading_fit_weights(v, vr)
    fit_l1, l1 = np.abs(fit - w).sum(), np.abs(est.weights - w).sum()
    assert np.isclose(est.weights.sum(), 1.0) and (est.weights >= 0).all()
    assert est.identifiable
    assert l1 <= max(2 * fit_l1, fit_l1 + 0.03), (w, est.weights, fit)


def test_rows_of_different_sizes_share_one_pass_and_trials_are_independent() -> None:
    rng = np.random.default_rng(3)
    truths = [sparse_truth(rng, n) for n in (2, 4, 6)]
    problems = [synthetic(rng, t, w) for t, w in zip((15, 300, 900), truths, strict=True)]
    est = estimate_groups(problems, opts=EstimateOptions(trials=5), rng=rng)
    for e, w in zip(est, truths, strict=True):
        assert e.weights.shape == w.shape and e.trial_std is not None
        assert (e.trial_std > 0).any() and (
            e.trial_std < e.std + 0.01
        ).all()  # sampler noise < posterior width
    assert np.abs(est[2].weights - truths[2]).sum() < 0.1


def test_parallel_behaviours_are_not_identifiable_and_the_prior_splits_them() -> None:
    rng = np.random.default_rng(8)
    t = 400
    a = rng.uniform(-1.2, 1.2, t)
    base = np.stack([np.cos(a), np.sin(a)], axis=-1)
    other = rng.uniform(-np.pi, np.pi, t)
    v = np.stack([0.8 * base, 0.5 * base, np.stack([np.cos(other), np.sin(other)], -1) * 0.6], axis=1)
    f = 0.3 * v[:, 0] + 0.3 * v[:, 1] + 0.4 * v[:, 2]
    th = np.arctan2(f[:, 1], f[:, 0]) + rng.normal(0, NOISE, t)
    vr = np.stack([np.cos(th), np.sin(th)], -1)
    est = estimate_group(v, vr, opts=EstimateOptions(trials=4), rng=rng)
    assert est.identifiable is False
    assert np.degrees(angle_errors(v, vr, est.weights).mean()) < 6.0  # the heading is still right
    assert est.std[0] > 3 * est.std[2] and est.std[1] > 3 * est.std[2]
    # the posterior splits the pair evenly in expectation: their means are within their spread
    assert abs(est.weights[0] - est.weights[1]) < est.std[0]


def test_single_behaviour_one_step_and_empty_groups() -> None:
    rng = np.random.default_rng(0)
    est = estimate_group(
        rng.normal(size=(20, 1, 2)), rng.normal(size=(20, 2)), opts=EstimateOptions(), rng=rng
    )
    assert est.weights.tolist() == [1.0] and est.std.tolist() == [0.0]
    v, vr = synthetic(rng, 1, np.array([0.2, 0.3, 0.5]))
    est = estimate_group(v, vr, opts=EstimateOptions(), rng=rng)
    assert np.isfinite(est.weights).all() and np.isclose(est.weights.sum(), 1.0)
    assert est.identifiable is False  # one step cannot pin three weights
    empty = estimate_group(np.zeros((0, 3, 2)), np.zeros((0, 2)), opts=EstimateOptions(), rng=rng)
    assert np.allclose(empty.weights, 1 / 3) and empty.identifiable is False


def test_the_paper_filter_is_worse_than_the_posterior() -> None:
    """The published likelihood 2 − D/2 is flat and its random walk forgets: on the same data the
    posterior is closer to the truth, over seeds."""
    l1: dict[str, list[float]] = {"pf": [], "paper": []}
    for seed in range(4):
        rng = np.random.default_rng(seed)
        w = sparse_truth(rng, 5)
        v, vr = synthetic(rng, 400, w)
        for method in l1:
            est = estimate_group(v, vr, opts=EstimateOptions(method=method), rng=np.random.default_rng(seed))  # type: ignore[arg-type]
            l1[method].append(float(np.abs(est.weights - w).sum()))
    assert np.mean(l1["pf"]) < np.mean(l1["paper"])


@pytest.mark.parametrize(("k", "m", "n"), [(1, 50, 3), (3, 40, 6), (2, 7, 1)])
def test_paper_filter_vectorised_step_agrees_with_a_per_particle_loop(k: int, m: int, n: int) -> None:
    rng = np.random.default_rng(k * 100 + m + n)
    p = PFParams(particles=m)
    s = rng.uniform(0, 1, (k, m, n))
    logw = rng.normal(0, 3, (k, m))  # uneven: forces resampling in some trials
    for _ in range(5):
        v = rng.normal(0, 0.5, (n, 2))
        vr = rng.normal(size=2)
        vr /= np.linalg.norm(vr)
        noise = rng.standard_normal((k, m, n))
        u = rng.uniform(0, 1, k)
        a = step(s, logw, v, vr, noise, u, 0.05, p)
        b = reference_step(s, logw, v, vr, noise, u, 0.05, p)
        for x, y in zip(a, b, strict=True):
            assert np.allclose(x, y, atol=1e-9)
        s, logw = a[0], a[1]


def test_paper_filter_trials_are_independent_and_vectorised() -> None:
    rng = np.random.default_rng(3)
    v, vr = synthetic(rng, 300, np.array([0.1, 0.2, 0.3, 0.4]))
    res = run_filter(v, vr, trials=6, rng=rng, params=PFParams(particles=300))
    assert res.weights.shape == (6, 4)
    assert len({tuple(np.round(r, 6)) for r in res.weights}) == 6


@pytest.mark.parametrize("seed", range(3))
def test_nnls_baseline_is_close_but_biased_by_magnitudes(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    w = rng.dirichlet(np.ones(5))
    v, vr = synthetic(rng, 600, w)
    est = nnls_weights(v, vr)
    assert (est >= 0).all() and np.abs(est / est.sum() - w).sum() <= 0.15


def test_arbitration_picks_the_best_single_behaviour() -> None:
    rng = np.random.default_rng(2)
    v, _ = synthetic(rng, 200, np.array([0.25, 0.25, 0.25, 0.25]))
    vr = v[:, 2] / np.linalg.norm(v[:, 2], axis=1, keepdims=True)
    assert arbitration_weights(v, vr).tolist() == [0.0, 0.0, 1.0, 0.0]
