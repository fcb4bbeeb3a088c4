"""The hierarchical prior of a discrete demo's rows: a row borrows strength from its step.

A person at a keyboard makes a few dozen decisions per goal segment, spread over its BACs: most
rows see a handful, and under the flat ``Dirichlet(α)`` prior a row of three decisions is little
more than a guess. Here a row's prior is centred on its *step's* weights — one weight vector fitted
to every decision of the goal segment (each behaviour's vector where it applies, nothing where
it does not) — restricted to the behaviours the row has and renormalised to ``m``:

``w_row ~ Dirichlet(α + c · m)``

with ``c ≥ 0`` the prior's strength (``c = 0``: the flat prior). ``c`` is learned from the demo,
by type-II maximum likelihood over the rows the data does not pin: each row's evidence
``Z_c = E_{w ~ Dirichlet(α + c m)}[p(data | w)]`` is estimated from :data:`PRIOR_DRAWS` draws of
that prior, and ``c`` (on :data:`SPREADS`) maximises their product. Such a row's estimate is then
the mean of those draws weighted by its likelihood (importance sampling from the prior: the
likelihood of a few decisions is broad). A row the data pins, a row of one behaviour, or one
whose draws give fewer than :data:`MIN_ESS` effective samples keeps its flat-prior estimate; the
flat pass's random stream is unchanged (the draws have their own).

The centre is fitted on the same decisions as the rows, so the evidence favours pooling more than
a held-out centre would; :data:`SPREADS` stops at a prior worth a few decisions.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.special import logsumexp

from lfdfuse.estimate.methods import RowEstimate

#: the prior strengths ``c`` tried (0: the flat prior)
SPREADS: tuple[float, ...] = (0.0, 1.0, 2.0, 4.0, 8.0)
#: fewest effective particles a reweighted row's estimate is taken from
MIN_ESS = 50.0
#: draws of the hierarchical prior for a row the flat posterior's particles cannot reweight
PRIOR_DRAWS = 4096


@dataclass(frozen=True)
class Hierarchy:
    """The chosen prior strength and the log evidence of each strength tried (for provenance)."""

    spread: float
    log_evidence: tuple[float, ...]  # Σ over rows of log(Z_c / Z_0), per :data:`SPREADS`


def centre_of(step_weights: np.ndarray, behaviors: Sequence[int]) -> np.ndarray:
    """The step's weights ``(K,)`` over ``behaviors`` (indices), renormalised; uniform when the
    step gives them no weight."""
    m = np.maximum(np.asarray(step_weights, dtype=np.float64)[list(behaviors)], 0.0)
    s = float(m.sum())
    return m / s if s > 1e-9 else np.full(len(m), 1.0 / len(m))


def _log_mean_lik(
    loglik: Callable[[np.ndarray], np.ndarray],
    centre: np.ndarray,
    alpha: float,
    c: float,
    rng: np.random.Generator,
) -> tuple[float, np.ndarray, np.ndarray]:
    """``log Z_c`` of a row by :data:`PRIOR_DRAWS` draws of ``Dirichlet(α + c m)``, with the draws
    and their log-likelihoods."""
    draws = np.maximum(rng.dirichlet(alpha + c * centre, PRIOR_DRAWS), 1e-300)
    draws /= draws.sum(axis=1, keepdims=True)
    ll = loglik(draws)
    return float(logsumexp(ll) - np.log(len(ll))), draws, ll


def hierarchical_rows(
    est: Sequence[RowEstimate],
    centres: Sequence[np.ndarray],
    logliks: Sequence[Callable[[np.ndarray], np.ndarray]],
    alpha: float,
    rng: np.random.Generator,
) -> tuple[list[RowEstimate], Hierarchy]:
    """The rows' estimates under the prior centred on their step's weights ``centres``, its
    strength ``c`` of :data:`SPREADS` the one with the largest evidence over the rows the data
    does not pin (each row's evidence by draws of its prior weighted by ``logliks``). A pinned
    row, a row of one behaviour, or one whose draws are too few to trust keeps its estimate."""
    open_rows = [
        i for i, (e, m) in enumerate(zip(est, centres, strict=True)) if not e.identifiable and len(m) >= 2
    ]
    if not open_rows:
        return list(est), Hierarchy(0.0, ())
    totals = []
    samples: list[list[tuple[np.ndarray, np.ndarray]]] = []
    for c in SPREADS:
        total = 0.0
        got = []
        for i in open_rows:
            z, draws, ll = _log_mean_lik(logliks[i], centres[i], alpha, c, rng)
            total += z
            got.append((draws, ll))
        totals.append(total)
        samples.append(got)
    best = int(np.argmax(totals))
    out = list(est)
    if SPREADS[best] > 0.0:
        for i, (draws, ll) in zip(open_rows, samples[best], strict=True):
            w = _weighted(est[i], draws, ll)
            if w is not None:
                out[i] = w
    return out, Hierarchy(SPREADS[best], tuple(totals))


def _weighted(est: RowEstimate, particles: np.ndarray, logp: np.ndarray) -> RowEstimate | None:
    """The estimate (mean, std) of ``particles (P, n)`` weighted by ``exp(logp)``; None when
    fewer than :data:`MIN_ESS` effective particles carry the weight."""
    p = np.exp(logp - logp.max())
    p /= p.sum()
    if 1.0 / float((p**2).sum()) < MIN_ESS:
        return None
    mean = p @ particles
    std = np.sqrt(np.maximum(p @ (particles - mean) ** 2, 0.0))
    return replace(est, weights=mean / mean.sum(), std=std)
