"""Does the data pin a row's weights, or does the prior?

A row is *identifiable* when, along every direction inside the simplex, the posterior variance is
well below the prior's: ``λ_max(Σ_post) < threshold · σ²_prior`` in the tangent space of the
simplex. Two behaviours that point the same way leave their split to the prior: the posterior
along that edge is about as wide as the prior, and the row says ``identifiable: false``.
"""

from __future__ import annotations

import numpy as np

from lfdfuse.estimate.model import FusionModel, prior_tangent_variance

#: the largest posterior-to-prior variance ratio (along any direction) that still counts as pinned
THRESHOLD = 0.25


def tangent_basis(n: int) -> np.ndarray:
    """An orthonormal basis ``(n, n−1)`` of the directions that keep ``Σ w`` fixed."""
    return np.asarray(np.linalg.svd(np.ones((1, n)))[2][1:].T)


def variance_ratio(cov: np.ndarray, model: FusionModel) -> float:
    """Largest posterior variance along a simplex direction over the prior's, for ``cov (n, n)``."""
    n = cov.shape[0]
    if n < 2:
        return 0.0
    b = tangent_basis(n)
    lam = float(np.linalg.eigvalsh(b.T @ cov @ b).max())
    return lam / prior_tangent_variance(n, model)


def identifiable(cov: np.ndarray, model: FusionModel, *, threshold: float = THRESHOLD) -> bool:
    """Whether the posterior ``cov (n, n)`` is narrower than the prior in every direction."""
    return variance_ratio(cov, model) < threshold
