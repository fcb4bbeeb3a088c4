"""The paper's particle filter over fusion weights (equations 1–8), vectorised over trials.

``--method paper``: kept as published, to reproduce the paper's figures. It is not the exact
posterior of any model — the random walk forgets data, clipping to ``[0, 1]^n`` acts as a hidden
prior, and short groups are replayed — which is why ``--method pf`` (:mod:`lfdfuse.estimate.smc`)
is the default.

State: ``K`` independent filters (trials) of ``M`` particles, each a weight vector in
``[0, 1]^n`` over the applicable behaviours. One step, given the behaviour vectors ``v (n, 2)``
and the demonstrated unit vector ``V_r (2,)`` of one timestep:

1. resample (systematic) the trials whose effective sample size fell below ``ess_fraction · M``;
2. move every particle by Gaussian noise (the motion model) and clip to ``[0, 1]``;
3. weight every particle by the likelihood of ``V_r`` given its normalised fused vector
   ``V̂ = Σ sₖ vₖ / |Σ sₖ vₖ|`` (eq. 7–8);
4. report the posterior mean.

Within a BAC the true weights are constant, so the random walk only keeps the cloud alive: its
standard deviation shrinks as ``σ₀ / sqrt(1 + t / τ)`` down to ``σ_min``. Two likelihoods:

* ``paper`` (default, as published): ``2 − D/2`` with ``D = |V_r − V̂|`` (eq. 7) — at most a
  factor 2 between the best and the worst particle, so each step carries little evidence;
* ``vonmises`` (the previous default of this project, kept for comparison): ``exp(κ (cos Δθ − 1))``, ``κ = 1 / σ_h²`` for an assumed heading noise
  ``σ_h`` — a Gaussian in the heading error for small errors.

Weights are multiplied across steps (log-domain) and reset to uniform after resampling, which is
the paper's per-step resampling when ``ess_fraction = 1``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from lfdfuse.estimate.resampling import ess, systematic
from lfdfuse.progress import Progress, tell

Likelihood = Literal["vonmises", "paper"]


@dataclass(frozen=True)
class PFParams:
    """Settings of the filter (see the module docstring)."""

    particles: int = 1000
    likelihood: Likelihood = "paper"
    heading_noise_rad: float = math.radians(10.0)  # σ_h of the von Mises likelihood
    jitter0: float = 0.08  # σ₀ of the motion model
    jitter_min: float = 0.003  # σ_min
    jitter_tau: float = 10.0  # τ, in steps
    ess_fraction: float = 0.5
    min_updates: int = 400  # short groups are passed over again until this many updates
    burn_in: float = 0.3  # the first share of the per-step means is left out of the average


def jitter(p: PFParams, t: int) -> float:
    return max(p.jitter_min, p.jitter0 / math.sqrt(1.0 + t / p.jitter_tau))


def log_likelihood(fused: np.ndarray, vr: np.ndarray, p: PFParams) -> np.ndarray:
    """Log-likelihood ``(...)`` of ``V_r (2,)`` for fused vectors ``(..., 2)`` (not normalised).

    A zero fused vector points nowhere: it gets the likelihood of a heading error of 90°.
    """
    norm = np.sqrt(fused[..., 0] ** 2 + fused[..., 1] ** 2)
    ok = norm > 1e-12
    safe = np.where(ok, norm, 1.0)
    cos = np.where(ok, (fused[..., 0] * vr[0] + fused[..., 1] * vr[1]) / safe, 0.0)
    if p.likelihood == "paper":
        d = np.sqrt(np.maximum(0.0, 2.0 - 2.0 * cos))  # |V_r − V̂| for unit vectors
        return np.log(2.0 - d / 2.0)
    kappa = 1.0 / p.heading_noise_rad**2
    return kappa * (cos - 1.0)


def step(
    s: np.ndarray,
    logw: np.ndarray,
    v: np.ndarray,
    vr: np.ndarray,
    noise: np.ndarray,
    u: np.ndarray,
    sigma: float,
    p: PFParams,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One filter step for all trials: particles ``s (K, M, n)``, log-weights ``(K, M)``.

    ``noise (K, M, n)`` are standard normal draws and ``u (K,)`` uniform draws for resampling,
    passed in so that a reference implementation can be fed the same random numbers.
    Returns the new particles, log-weights and posterior means ``(K, n)``.
    """
    k, m, n = s.shape
    need = np.nonzero(ess(logw) < p.ess_fraction * m)[0]
    if len(need):
        idx = systematic(logw[need], u[need])
        flat = s[need].reshape(-1, n)
        s = s.copy()
        s[need] = flat[(idx + (np.arange(len(need)) * m)[:, None]).ravel()].reshape(len(need), m, n)
        logw = logw.copy()
        logw[need] = 0.0
    s = s + sigma * noise
    np.clip(s, 0.0, 1.0, out=s)
    fused = s @ v  # (K, M, 2)
    logw = logw + log_likelihood(fused, vr, p)
    logw -= logw.max(axis=1, keepdims=True)
    w = np.exp(logw)
    mean = (w[:, None, :] @ s)[:, 0, :] / w.sum(axis=1)[:, None]
    return s, logw, mean


@dataclass(frozen=True)
class PFResult:
    """Normalised weights per trial ``(K, n)`` and the posterior spread of each trial ``(K, n)``."""

    weights: np.ndarray
    spread: np.ndarray
    updates: int


def normalise(w: np.ndarray) -> np.ndarray:
    """Rows scaled to sum 1 (uniform where a row sums to 0)."""
    tot = w.sum(axis=-1, keepdims=True)
    n = w.shape[-1]
    return np.where(tot > 1e-12, w / np.where(tot > 1e-12, tot, 1.0), 1.0 / n)


#: updates of the filter between two progress reports
PROGRESS_EVERY = 25


def run_filter(
    vectors: np.ndarray,
    demo: np.ndarray,
    *,
    trials: int,
    rng: np.random.Generator,
    params: PFParams,
    progress: Progress | None = None,
) -> PFResult:
    """Filter one group: ``vectors (T, n, 2)``, ``demo (T, 2)`` → per-trial weights.

    The per-step posterior means (normalised to sum 1) after a burn-in are averaged, after
    dropping outlying steps (farther than 3 median absolute deviations from the median).
    ``progress`` is told ``(updates done, updates)`` every :data:`PROGRESS_EVERY` updates.
    """
    t_count, n, _ = vectors.shape
    k, m = trials, params.particles
    s = rng.uniform(0.0, 1.0, (k, m, n))
    logw = np.zeros((k, m))
    passes = max(1, math.ceil(params.min_updates / max(t_count, 1)))
    order = np.concatenate(
        [np.arange(t_count) if i == 0 else rng.permutation(t_count) for i in range(passes)]
    )
    means = np.empty((len(order), k, n))
    for t, j in enumerate(order):
        noise = rng.standard_normal((k, m, n))
        u = rng.uniform(0.0, 1.0, k)
        s, logw, mean = step(s, logw, vectors[j], demo[j], noise, u, jitter(params, t), params)
        means[t] = mean
        if progress is not None and (t + 1) % PROGRESS_EVERY == 0:
            tell(progress, t + 1.0, float(len(order)))
    kept = normalise(means[int(params.burn_in * len(order)) :])  # (T', K, n)
    med = np.median(kept, axis=0)
    dev = np.abs(kept - med).sum(axis=2)  # (T', K)
    mad = np.median(dev, axis=0) + 1e-9
    inlier = dev <= 3.0 * mad[None, :] + 1e-6
    wsum = (kept * inlier[:, :, None]).sum(axis=0) / np.maximum(inlier.sum(axis=0), 1)[:, None]
    w = np.exp(logw - logw.max(axis=1, keepdims=True))
    w /= w.sum(axis=1, keepdims=True)
    ns = normalise(s)
    pmean = (w[:, :, None] * ns).sum(axis=1)
    spread = np.sqrt((w[:, :, None] * (ns - pmean[:, None, :]) ** 2).sum(axis=1))
    tell(progress, float(len(order)), float(len(order)))
    return PFResult(normalise(wsum), spread, len(order))


def reference_step(
    s: np.ndarray,
    logw: np.ndarray,
    v: np.ndarray,
    vr: np.ndarray,
    noise: np.ndarray,
    u: np.ndarray,
    sigma: float,
    p: PFParams,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The same step as :func:`step`, one particle at a time in plain Python (for tests and benches)."""
    k, m, n = s.shape
    s = s.copy()
    logw = logw.copy()
    means = np.zeros((k, n))
    for a in range(k):
        top = max(logw[a])
        ws = [math.exp(x - top) for x in logw[a]]
        tot = sum(ws)
        e = 1.0 / sum((x / tot) ** 2 for x in ws)
        if e < p.ess_fraction * m:
            cum, acc = [], 0.0
            for x in ws:
                acc += x
                cum.append(acc)
            cum = [c / acc for c in cum]
            cum[-1] = 1.0
            new = []
            j = 0
            for i in range(m):
                pos = (u[a] + i) / m
                while j < m - 1 and cum[j] <= pos:
                    j += 1
                new.append(s[a, j].copy())
            s[a] = np.array(new)
            logw[a] = 0.0
        for i in range(m):
            fx = fy = 0.0
            for b in range(n):
                s[a, i, b] = min(1.0, max(0.0, s[a, i, b] + sigma * noise[a, i, b]))
                fx += s[a, i, b] * v[b, 0]
                fy += s[a, i, b] * v[b, 1]
            logw[a, i] += float(log_likelihood(np.array([fx, fy]), vr, p))
        top = max(logw[a])
        logw[a] = logw[a] - top
        ws = [math.exp(x) for x in logw[a]]
        tot = sum(ws)
        for b in range(n):
            means[a, b] = sum(ws[i] * s[a, i, b] for i in range(m)) / tot
    return s, logw, means
