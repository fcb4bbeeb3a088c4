"""A fused heading read as a person's key press: what the discrete command model predicts.

A person at a keyboard (the ``discrete`` command model, :mod:`lfdfuse.estimate.model`) can only
hold one of their keys; the model says they press the key whose bin the noisy fused heading
``φ + ε`` falls in. Two read-outs of a fitted table follow from it:

* **the heading** (:func:`key_heading`): the heading of the key whose bin holds ``φ``. The noise
  ``ε`` is symmetric and the bins are ordered by heading, so this is the median of the model's
  predicted heading — the prediction with the least expected absolute heading error — and it
  has no parameter of its own;
* **the key** (:class:`KeyResponse`): the most probable key given ``φ``,
  ``P(c | φ) ∝ π_c · ((1 − λ) P_κ(φ + ε ∈ bin c) + λ / m)``, with ``π`` how often the person
  pressed each key and ``κ`` (the noise of their choices about the fused heading) fitted by
  maximum likelihood over the model's ``κ`` nodes, both on the *training* decisions only
  (:func:`fit_key_response`). Where the fused heading says little about the key, ``κ`` is small
  and the key the person presses most wins; where it says much, the key whose bin holds ``φ``.

Measured on the 13 human drives (``evaluate``'s blocked 5-fold; every fitted method and the
oracle read the same way; ``tests/bench/person_corpus.py``): fused's mean error 31.5° → 26.9°;
fused ≤ 'straight' on 3 → 6 of 10 drives; below 'straight' on the turning steps 9 → 8 of 10 (one
drive is now predicted forward throughout, a tie); key accuracy ≥ 'straight''s on 7 → 8 of 9 —
the heading read-out alone leaves it at 7; the key response lifts one drive from 24 % to 44 % (a
tie with 'straight') and two others, lowers four by 2–6 points, mean 37.8 % → 39.6 %; fused −
oracle median 7.1° → 6.1°. Tried and not kept: a dead band (forward while ``|φ| < θ``, ``θ``
fitted on the training steps or decisions: ≤ 'straight' on 5 of 10 at best, keys 4–7 of 9), a
gain ``φ → sφ`` fitted likewise (3 of 10), and the median of the key response as the heading
(keys 8 of 9 but turns 7 of 10, fused − oracle 11°). The continuous gamepad drive is unchanged:
fused 30.7° against straight's 20.1°.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lfdfuse.estimate.discrete_kernels import cdf_at
from lfdfuse.estimate.model import CommandBins, FusionModel

#: added to every key's count of training presses (a key never pressed keeps a chance)
PSEUDO_COUNT = 0.5


def _wrap(a: np.ndarray) -> np.ndarray:
    return np.asarray(np.arctan2(np.sin(a), np.cos(a)))


def key_of(bins: CommandBins, heading: np.ndarray) -> np.ndarray:
    """The key (index into ``bins``) whose bin holds each heading (rad)."""
    e = bins.edges
    return np.asarray(np.clip(np.searchsorted(e, _wrap(heading), side="right") - 1, 0, bins.size - 1))


def key_heading(bins: CommandBins, heading: np.ndarray) -> np.ndarray:
    """The heading (rad) of the key whose bin holds each heading: the model's median prediction.

    >>> b = CommandBins.from_headings([0.0, 0.66, -0.66])
    >>> key_heading(b, np.array([0.2, 0.4, -1.0])).round(2).tolist()
    [0.0, 0.66, -0.66]
    """
    return np.asarray(np.array(bins.headings)[key_of(bins, heading)])


def bin_probabilities(bins: CommandBins, heading: np.ndarray, model: FusionModel) -> np.ndarray:
    """``P_κ(φ + ε ∈ bin c)`` ``(N, J, m)`` for headings ``φ (N,)`` at every discrete ``κ`` node
    of ``model`` (``ε`` von Mises, as the estimator's likelihood reads it)."""
    e = bins.edges
    lo = _wrap(e[None, :-1] - np.asarray(heading)[:, None])  # (N, m)
    width = (e[1:] - e[:-1])[None, :]
    hi = lo + width
    wrap = hi > math.pi
    table = model.vm_cdf_rows
    p = cdf_at(np.where(wrap, hi - 2.0 * math.pi, hi), table) + wrap[..., None] - cdf_at(lo, table)
    return np.asarray(np.clip(p, 0.0, 1.0).transpose(0, 2, 1))


@dataclass(frozen=True)
class KeyResponse:
    """Which key a person presses given the fused heading (see the module docstring)."""

    bins: CommandBins
    frequencies: tuple[float, ...]  # π: each key's share of the training presses (smoothed)
    sigma_deg: float  # the fitted noise of the choices about the fused heading, σ = 1/√κ
    lapse: float

    def probabilities(self, heading: np.ndarray, model: FusionModel) -> np.ndarray:
        """``P(c | φ)`` ``(N, m)`` for headings ``φ (N,)`` (rad)."""
        node = int(np.argmin(np.abs(np.degrees(1.0 / np.sqrt(model.discrete_kappas)) - self.sigma_deg)))
        return _posterior(self.bins, heading, model, np.array(self.frequencies), self.lapse)[:, node, :]

    def key(self, heading: np.ndarray, model: FusionModel) -> np.ndarray:
        """The most probable key of each heading (rad); a tie goes to the lower index."""
        if len(heading) == 0:
            return np.zeros(0, dtype=np.int64)
        return np.asarray(np.argmax(self.probabilities(heading, model), axis=1))

    def provenance(self) -> dict[str, object]:
        return {
            "sigma_deg": round(self.sigma_deg, 2),
            "key_shares": {
                f"{math.degrees(h):.0f}°": round(f, 3)
                for h, f in zip(self.bins.headings, self.frequencies, strict=True)
            },
        }


def _posterior(
    bins: CommandBins, heading: np.ndarray, model: FusionModel, prior: np.ndarray, lapse: float
) -> np.ndarray:
    """``P(c | φ)`` ``(N, J, m)`` at every ``κ`` node."""
    p = (1.0 - lapse) * bin_probabilities(bins, heading, model) + lapse / bins.size
    p = p * prior[None, None, :]
    return np.asarray(p / p.sum(axis=-1, keepdims=True))


def fit_key_response(
    bins: CommandBins, heading: np.ndarray, keys: np.ndarray, model: FusionModel
) -> KeyResponse:
    """The key response fitted on training decisions: fused headings ``heading (N,)`` (rad) and
    the keys pressed ``keys (N,)`` (indices into ``bins``; negative — a stop, a reverse — are
    left out). ``π`` the smoothed shares of the keys, ``κ`` the node of ``model``'s discrete grid
    with the greatest likelihood of the keys (the larger ``σ`` on a tie)."""
    ok = np.asarray(keys) >= 0
    h, k = np.asarray(heading)[ok], np.asarray(keys)[ok].astype(np.int64)
    counts = np.bincount(k, minlength=bins.size)[: bins.size].astype(np.float64) + PSEUDO_COUNT
    prior = counts / counts.sum()
    sigmas = np.degrees(1.0 / np.sqrt(model.discrete_kappas))  # descending: the broadest first
    if len(k) == 0:
        return KeyResponse(bins, tuple(prior.tolist()), float(sigmas[0]), model.lapse)
    post = _posterior(bins, h, model, prior, model.lapse)  # (N, J, m)
    ll = np.log(np.maximum(post[np.arange(len(k)), :, k], 1e-300)).sum(axis=0)  # (J,)
    return KeyResponse(bins, tuple(prior.tolist()), float(sigmas[int(np.argmax(ll))]), model.lapse)
