"""Baselines beside the particle filter: non-negative least squares and arbitration."""

from __future__ import annotations

import numpy as np


def nnls(a: np.ndarray, b: np.ndarray, *, max_iter: int | None = None) -> np.ndarray:
    """Solve ``min ‖A x − b‖`` subject to ``x ≥ 0`` (Lawson–Hanson active set).

    ``a (R, n)``, ``b (R,)`` → ``x (n,)``.

    >>> import numpy as np
    >>> nnls(np.eye(2), np.array([1.0, -1.0])).tolist()
    [1.0, 0.0]
    """
    r, n = a.shape
    x = np.zeros(n)
    passive = np.zeros(n, dtype=bool)
    limit = max_iter if max_iter is not None else 3 * n + 10
    tol = 1e-10 * max(1.0, float(np.abs(a).max(initial=0.0))) * max(r, n)
    for _ in range(limit):
        grad = a.T @ (b - a @ x)
        cand = ~passive & (grad > tol)
        if not cand.any():
            break
        passive[int(np.argmax(np.where(cand, grad, -np.inf)))] = True
        while True:
            z = np.zeros(n)
            z[passive] = np.linalg.lstsq(a[:, passive], b, rcond=None)[0]
            if (z[passive] > 0).all():
                x = z
                break
            neg = passive & (z <= 0)
            alpha = np.min(x[neg] / (x[neg] - z[neg]))
            x = x + alpha * (z - x)
            passive &= x > tol
            x[~passive] = 0.0
    return x


def nnls_weights(vectors: np.ndarray, demo: np.ndarray) -> np.ndarray:
    """Weights ``(n,)`` with ``Σ sₖ vₖ ≈ V_r`` in least squares, ``s ≥ 0``: ``vectors (T, n, 2)``."""
    t, n, _ = vectors.shape
    a = vectors.transpose(0, 2, 1).reshape(2 * t, n)
    return nnls(a, demo.reshape(2 * t))


def angle_errors(vectors: np.ndarray, demo: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Heading errors ``(T,)`` in radians between the fused vector and ``V_r`` (π where fused is 0)."""
    f = np.einsum("tnd,n->td", vectors, weights)
    zero = np.hypot(f[:, 0], f[:, 1]) <= 1e-12
    d = np.arctan2(f[:, 1], f[:, 0]) - np.arctan2(demo[:, 1], demo[:, 0])
    return np.where(zero, np.pi, np.abs(np.arctan2(np.sin(d), np.cos(d))))


def arbitration_weights(vectors: np.ndarray, demo: np.ndarray) -> np.ndarray:
    """The single behaviour whose own heading best matches the demonstration (weight 1)."""
    n = vectors.shape[1]
    errs = [angle_errors(vectors, demo, np.eye(n)[i]).mean() for i in range(n)]
    w = np.zeros(n)
    w[int(np.argmin(errs))] = 1.0
    return w
