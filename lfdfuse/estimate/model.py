"""The statistical model of one fusion row: what ``--method pf`` computes the posterior of.

Given the applicable behaviours' vectors ``vₜₖ`` and the demonstrated unit heading ``uₜ`` of the
``T`` informative steps of one (goal segment, BAC):

* **weights** ``w`` on the simplex ``Δⁿ⁻¹`` (``wₖ ≥ 0``, ``Σ wₖ = 1``): only the *direction* of the
  fused vector ``fₜ = Σₖ wₖ vₜₖ`` reaches the robot, so the scale of the weights is not
  identifiable and is fixed by the simplex rather than by clipping;
* **prior** ``w ~ Dirichlet(α, …, α)`` with ``α = ½`` by default — the Jeffreys prior of a
  categorical, mildly favouring rows where a few behaviours carry the weight, as a designer
  writes them. Measured on round trips against hand-written sparse tables: with ``α = 1`` every
  weight whose truth is 0 keeps ~0.01–0.02 of posterior mean, and rows the data pins missed by
  2–4× the L1 of a least-squares heading fit; with ``α = ½`` they are within it. Where the
  data cannot split two behaviours the prior still decides, symmetrically (equal means);
* **heading noise**: the angle ``Δₜ`` between ``uₜ`` and ``fₜ`` is von Mises with concentration
  ``κ`` around 0, independent over steps: ``p(uₜ | w, κ) = exp(κ cos Δₜ) / (2π I₀(κ))``;
* **κ is marginalised**: log-uniform in the noise scale ``σ = 1/√κ`` between ``sigma_min_deg``
  and ``sigma_max_deg``, integrated on a grid. The likelihood depends on ``w`` only through
  ``S(w) = Σₜ cos Δₜ``, so integrating ``κ`` out costs a ``logsumexp`` per particle.

A zero fused vector points nowhere; it counts as ``cos Δ = 0`` (a 90° error). The von Mises
loss ``1 − cos Δ`` is bounded, so a few wild steps (the teacher's safety reflex) cannot pull the
weights far: the fitted ``κ`` drops instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.special import i0e, logsumexp


@dataclass(frozen=True)
class FusionModel:
    """Prior and noise model of a fusion row (see the module docstring)."""

    alpha: float = 0.5  # Dirichlet concentration of every weight (see the module docstring)
    sigma_min_deg: float = 0.5  # range of the log-uniform prior on the heading noise σ = 1/√κ
    sigma_max_deg: float = 90.0
    kappa_points: int = 48  # quadrature nodes for integrating κ out

    @cached_property
    def kappas(self) -> np.ndarray:
        """Quadrature nodes ``(J,)`` of ``κ``, equally spaced in ``log σ`` (the prior's measure)."""
        sig = np.radians(np.geomspace(self.sigma_max_deg, self.sigma_min_deg, self.kappa_points))
        return np.asarray(1.0 / sig**2)

    @cached_property
    def _log_norm(self) -> np.ndarray:
        """``log(2π I₀(κ)) − κ`` per node ``(J,)`` (the scaled Bessel function keeps it finite)."""
        k = self.kappas
        return np.asarray(math.log(2.0 * math.pi) + np.log(i0e(k)))


@dataclass(frozen=True)
class RowData:
    """The steps of one row, reduced to what the likelihood needs.

    ``along (T, n)``: each behaviour vector's component along the demonstrated heading;
    ``across (T, n)``: its component to the left of it. The fused vector's heading error is then
    ``atan2(across @ w, along @ w)``.
    """

    along: np.ndarray
    across: np.ndarray

    @property
    def steps(self) -> int:
        return int(self.along.shape[0])

    @property
    def size(self) -> int:
        return int(self.along.shape[1])


def row_data(vectors: np.ndarray, demo: np.ndarray) -> RowData:
    """``vectors (T, n, 2)`` and demonstrated headings ``demo (T, 2)`` (any length) → RowData."""
    u = demo / np.maximum(np.hypot(demo[:, 0], demo[:, 1]), 1e-12)[:, None]
    along = vectors[..., 0] * u[:, None, 0] + vectors[..., 1] * u[:, None, 1]
    across = u[:, None, 0] * vectors[..., 1] - u[:, None, 1] * vectors[..., 0]
    return RowData(np.ascontiguousarray(along), np.ascontiguousarray(across))


def cos_errors(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``cos Δ`` from the fused vector's components along / across the demo (0 where it is 0)."""
    r = np.hypot(a, b)
    return np.where(r > 1e-12, a / np.maximum(r, 1e-12), 0.0)


#: elements of a (steps × particles) temporary when summing over a row: steps are taken in blocks
#: of this size over the particle count, so an hour-long demo or 30 trials cost the same memory
#: as a minute-long one
BLOCK_ELEMENTS = 1 << 21


def sum_cos(data: RowData, w: np.ndarray) -> np.ndarray:
    """The sufficient statistic ``S = Σₜ cos Δₜ`` for weight vectors ``w (P, n)`` → ``(P,)``."""
    wt = np.ascontiguousarray(w.T)
    s = np.zeros(w.shape[0])
    block = max(16, BLOCK_ELEMENTS // max(1, w.shape[0]))
    for c in range(0, data.steps, block):
        a = data.along[c : c + block] @ wt
        b = data.across[c : c + block] @ wt
        r = np.hypot(a, b)
        s += (a / np.maximum(r, 1e-12)).sum(axis=0)
    return s


def log_marginal(s: np.ndarray, steps: np.ndarray | int, model: FusionModel) -> np.ndarray:
    """``log p(u₁…u_T | w)`` with ``κ`` integrated out, from ``S (…)`` and ``T`` (broadcast).

    The von Mises log-likelihood at node ``κⱼ`` is ``κⱼ (S − T) − T (log 2π I₀(κⱼ) − κⱼ)``.
    """
    t = np.asarray(steps, dtype=np.float64)[..., None]
    k = model.kappas
    terms = k * (s[..., None] - t) - t * model._log_norm
    # a log-sum-exp over the κ nodes in place (scipy's makes several copies of the (…, J) array)
    top = terms.max(axis=-1)
    terms -= top[..., None]
    np.exp(terms, out=terms)
    return np.asarray(top + np.log(terms.sum(axis=-1)) - math.log(len(k)))


def kappa_posterior(s: float, steps: int, model: FusionModel) -> np.ndarray:
    """Posterior weights of the ``κ`` nodes ``(J,)`` given ``S`` (for reporting the noise)."""
    k = model.kappas
    terms = k * (s - steps) - steps * model._log_norm
    p = np.exp(terms - terms.max())
    return np.asarray(p / p.sum())


def log_prior_alr(logw: np.ndarray, mask: np.ndarray, model: FusionModel) -> np.ndarray:
    """Log-density of the Dirichlet prior in additive-log-ratio coordinates, Jacobian included.

    With ``yᵢ = log(wᵢ / w_ref)`` the Jacobian of ``y → w`` is ``Πₖ wₖ``, so the density is
    ``Π wₖ^(α−1) · Π wₖ = Π wₖ^α`` up to a constant. ``logw (…, n)``, ``mask (…, n)`` marks the
    behaviours that exist in the row (padding is ignored).
    """
    return np.asarray(model.alpha * np.where(mask, logw, 0.0).sum(axis=-1))


def sample_prior(
    shape: tuple[int, ...], mask: np.ndarray, model: FusionModel, rng: np.random.Generator
) -> np.ndarray:
    """Log-weights ``(*shape, n)`` drawn from the Dirichlet prior over the masked behaviours.

    Drawn in log space (``log Gamma(α)`` variates) so that no weight underflows to −inf.
    """
    n = mask.shape[-1]
    # a Gamma(α) variate is U^(1/α)·Gamma(α+1): its log stays finite even for tiny α
    lg = (
        np.log(rng.gamma(model.alpha + 1.0, 1.0, (*shape, n)))
        + np.log(np.maximum(rng.uniform(0.0, 1.0, (*shape, n)), 1e-300)) / model.alpha
    )
    lg = np.where(mask, lg, -np.inf)
    return np.asarray(lg - logsumexp(lg, axis=-1, keepdims=True))


def prior_tangent_variance(n: int, model: FusionModel) -> float:
    """Variance of the symmetric Dirichlet prior along any unit direction inside the simplex.

    Its covariance is ``c (I − 11ᵀ/n)`` with ``c = 1 / (n (nα + 1))``.
    """
    return 1.0 / (n * (n * model.alpha + 1.0))
