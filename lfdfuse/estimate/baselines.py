"""Baselines beside the sampler: non-negative least squares, a least-squares heading fit on the
simplex, and arbitration (the best single behaviour, the pre-fusion approach).

scipy.optimize is imported where a baseline is fitted: every command that names the methods
(``inspect``, ``plot``, ``execute``'s summary) imports this module, and only a fit needs it.
"""

from __future__ import annotations

import numpy as np

from lfdfuse.estimate.model import row_data


def nnls_weights(vectors: np.ndarray, demo: np.ndarray) -> np.ndarray:
    """Weights ``(n,)`` with ``Σ sₖ vₖ ≈ V_r`` in least squares, ``s ≥ 0``: ``vectors (T, n, 2)``.

    It fits the unit ``V_r`` with the fused vector's length too, so it is biased by the
    behaviours' magnitudes.

    >>> import numpy as np
    >>> nnls_weights(np.array([[[1.0, 0.0], [0.0, 1.0]]]), np.array([[1.0, 0.0]])).round(6).tolist()
    [1.0, 0.0]
    """
    from scipy.optimize import nnls

    t, n, _ = vectors.shape
    a = vectors.transpose(0, 2, 1).reshape(2 * t, n)
    return np.asarray(nnls(a, demo.reshape(2 * t))[0])


def angle_errors(vectors: np.ndarray, demo: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Heading errors ``(T,)`` in radians between the fused vector and ``V_r`` (π where fused is 0)."""
    f = np.einsum("tnd,n->td", vectors, weights)
    zero = np.hypot(f[:, 0], f[:, 1]) <= 1e-12
    d = np.arctan2(f[:, 1], f[:, 0]) - np.arctan2(demo[:, 1], demo[:, 0])
    return np.asarray(np.where(zero, np.pi, np.abs(np.arctan2(np.sin(d), np.cos(d)))))


def heading_fit_weights(vectors: np.ndarray, demo: np.ndarray) -> np.ndarray:
    """Least-squares heading fit: ``w`` on the simplex minimising ``Σₜ Δₜ(w)²`` (radians).

    Several starts (uniform, NNLS, each vertex); the best local optimum wins. A baseline for
    round trips: where it lands close to the truth, the data pins the row.
    """
    from scipy.optimize import least_squares

    t, n, _ = vectors.shape
    if n == 1 or t == 0:
        return np.full(n, 1.0 / n)
    d = row_data(vectors, demo)

    def res(x: np.ndarray) -> np.ndarray:
        a, b = d.along @ x, d.across @ x
        return np.append(np.arctan2(b, a), x.sum() - 1.0)

    def jac(x: np.ndarray) -> np.ndarray:
        a, b = d.along @ x, d.across @ x
        r2 = np.maximum(a * a + b * b, 1e-12)
        j = (a[:, None] * d.across - b[:, None] * d.along) / r2[:, None]
        return np.vstack([j, np.ones((1, n))])

    starts = [np.full(n, 1.0 / n), *np.eye(n)]
    nn = nnls_weights(vectors, demo)
    if nn.sum() > 1e-9:
        starts.append(nn / nn.sum())
    best, cost = starts[0], np.inf
    for x0 in starts:
        x0 = np.clip(x0, 1e-6, None)
        sol = least_squares(res, x0 / x0.sum(), jac=jac, bounds=(0.0, np.inf), method="trf")
        if sol.cost < cost:
            best, cost = sol.x, sol.cost
    tot = best.sum()
    return np.asarray(best / tot) if tot > 1e-12 else np.full(n, 1.0 / n)


def arbitration_weights(vectors: np.ndarray, demo: np.ndarray) -> np.ndarray:
    """The single behaviour whose own heading best matches the demonstration (weight 1)."""
    n = vectors.shape[1]
    errs = [angle_errors(vectors, demo, np.eye(n)[i]).mean() for i in range(n)]
    w = np.zeros(n)
    w[int(np.argmin(errs))] = 1.0
    return w
