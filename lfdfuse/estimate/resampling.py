"""Resampling schemes: pure functions over log-weights, batched over independent chains.

Every function takes log-weights ``(C, M)`` — ``C`` independent particle systems (rows × trials)
of ``M`` particles each — and never a global RNG: the uniforms are drawn by the caller's
``numpy.random.Generator`` (or passed in, for tests).
"""

from __future__ import annotations

import numpy as np


def normalised(logw: np.ndarray) -> np.ndarray:
    """Weights ``(C, M)`` summing to 1 along the last axis, from log-weights (−inf allowed)."""
    top = np.max(logw, axis=-1, keepdims=True)
    w = np.exp(logw - np.where(np.isfinite(top), top, 0.0))
    return np.asarray(w / w.sum(axis=-1, keepdims=True))


def ess(logw: np.ndarray) -> np.ndarray:
    """Effective sample size ``(C,)``: ``(Σw)² / Σw²``, in ``[1, M]``.

    >>> import numpy as np
    >>> ess(np.zeros((1, 4))).tolist()
    [4.0]
    """
    w = normalised(logw)
    return np.asarray(1.0 / np.einsum("cm,cm->c", w, w))


def systematic(logw: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Systematic resampling: ancestor indices ``(C, M)`` in ``[0, M)``, given ``u (C,)`` in [0, 1).

    Particle ``j`` is copied ``⌊M wⱼ⌋`` or ``⌈M wⱼ⌉`` times; ancestors come out sorted.
    """
    c, m = logw.shape
    cs = np.cumsum(normalised(logw), axis=1)
    cs[:, -1] = 1.0
    pos = (u[:, None] + np.arange(m)[None, :]) / m
    offs = np.arange(c)[:, None] * 2.0  # disjoint ranges let one searchsorted serve every chain
    idx = np.searchsorted((cs + offs).ravel(), (pos + offs).ravel(), side="right").reshape(c, m)
    return np.asarray(np.minimum(idx - np.arange(c)[:, None] * m, m - 1))


def multinomial(logw: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Multinomial resampling: ``M`` independent draws per chain, ancestor indices ``(C, M)``."""
    c, m = logw.shape
    cs = np.cumsum(normalised(logw), axis=1)
    cs[:, -1] = 1.0
    u = rng.uniform(0.0, 1.0, (c, m))
    return np.asarray(np.minimum((cs[:, None, :] <= u[:, :, None]).sum(axis=2), m - 1))


def resample(logw: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The default scheme (systematic): ancestor indices ``(C, M)``."""
    return systematic(logw, np.asarray(rng.uniform(0.0, 1.0, logw.shape[0])))


def gather(x: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Particles ``x (C, M, …)`` picked by ancestor indices ``idx (C, M)``."""
    return np.take_along_axis(x, idx.reshape(idx.shape + (1,) * (x.ndim - 2)), axis=1)
