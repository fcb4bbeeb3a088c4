"""Tempered SMC with resample-move: the sampler of ``--method pf``, batched over rows × trials.

The target of chain ``c`` (row ``r``, trial ``k``) moves from the prior to the posterior of
:mod:`lfdfuse.estimate.model` through ``π_β ∝ prior · L^β``, ``0 = β₀ < β₁ < … < 1``. One
iteration (``__next__``):

1. choose the next ``β`` per chain by bisection so that the effective sample size of the
   incremental weights ``L^(β' − β)`` is ``ess_target · M`` (adaptive tempering);
2. resample (systematic);
3. rejuvenate: ``moves`` random-walk Metropolis steps in additive-log-ratio coordinates with
   the Dirichlet density and Jacobian, the proposal covariance the particle covariance (scaled
   by an acceptance-tuned factor). Each step leaves ``π_β`` invariant.

A chain that has reached ``β = 1`` keeps moving until it has made ``final_moves`` moves there;
then it is frozen. Every chain ends with ``M`` equally weighted draws from its posterior, for any
number of steps in the row — nothing is forgotten and nothing is replayed.

Rows of different sizes share one pass: the particle arrays are padded to the largest row's
behaviours (masked out of the simplex); only the likelihood loops over rows, one matrix product
each. The model enters only through ``log p(data | w)`` per particle
(:func:`~lfdfuse.estimate.model.row_loglik`): continuous and discrete rows share a pass.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from lfdfuse.estimate.kernels import LOG_MARGINAL, SUM_COS, logsumexp_last
from lfdfuse.estimate.model import FusionModel, Row, RowData, row_loglik, sample_prior
from lfdfuse.estimate.resampling import gather, resample
from lfdfuse.estimate.smc_kernels import (
    MOVE_FRAME,
    MOVE_PROPOSE,
    NEXT_DELTA,
    move_frame_reference,
    move_propose_reference,
    next_delta_reference,
)


@dataclass(frozen=True)
class SMCParams:
    """Settings of the sampler (see the module docstring)."""

    particles: int = 384
    #: a pass of discrete command-model rows holding at most ``discrete_few`` decisions in all
    #: runs with ``discrete_factor`` × ``particles``: few decisions leave a broad, flat-topped
    #: posterior (bins) whose mean settles slowly, and such a pass is cheap
    discrete_factor: int = 4
    discrete_few: int = 400
    ess_target: float = 0.5
    moves: int = 3  # Metropolis moves after each resampling
    final_moves: int = 6  # moves at β = 1 before a chain is frozen
    max_iterations: int = 500


@dataclass(frozen=True)
class SMCResult:
    """Per chain ``(C, …)``: particles' log-weights ``(C, M, n)``, mask ``(C, n)``, evidence."""

    logw: np.ndarray
    mask: np.ndarray
    log_evidence: np.ndarray
    iterations: int
    acceptance: np.ndarray  # mean Metropolis acceptance per chain

    @property
    def weights(self) -> np.ndarray:
        return np.asarray(np.exp(self.logw))

    def mean(self) -> np.ndarray:
        """Posterior means ``(C, n)`` (zero on padding)."""
        return np.asarray(self.weights.mean(axis=1))

    def cov(self) -> np.ndarray:
        """Posterior covariances ``(C, n, n)``."""
        w = self.weights
        d = w - w.mean(axis=1, keepdims=True)
        return np.asarray(np.einsum("cmi,cmj->cij", d, d) / max(1, w.shape[1] - 1))


def subset_exact(data: Row) -> bool:
    """Whether the likelihood of a subset of particles is, particle by particle, the number the
    whole set gets (``row_loglik(..., of=)``): a continuous row with the compiled kernels, where
    each particle's sum runs on its own. The numpy reference blocks its products by the particle
    count, so there it is not."""
    return isinstance(data, RowData) and SUM_COS.ready() and LOG_MARGINAL.ready()


class _Rows:
    """The rows' data; ``log p(data | w)`` per row (one BLAS product per block of steps)."""

    def __init__(self, rows: Sequence[Row], model: FusionModel) -> None:
        self.rows = list(rows)
        self.sizes = [r.size for r in rows]
        self.model = model

    def loglik(self, w: np.ndarray, active: np.ndarray, chains: np.ndarray | None = None) -> np.ndarray:
        """``log p (R, P)`` for weights ``w (R, P, n)``; rows not ``active (R,)`` are left at 0.

        ``chains (R, K)``: the trials (each ``P / K`` particles) of a row that are wanted; where
        the compiled likelihood gives each particle the number it gets among all
        (:func:`subset_exact`) only those are computed, the rest left
        at 0 (a row's trials finish at different iterations). A batched 3-D product is an
        order of magnitude slower here than a loop of 2-D ones.
        """
        out = np.zeros(w.shape[:2])
        for i in np.nonzero(active)[0]:
            data, wi = self.rows[i], w[i, :, : self.sizes[i]]
            if chains is not None and not chains[i].all() and subset_exact(data):
                k = chains.shape[1]
                m = wi.shape[0] // k
                keep = np.repeat(chains[i], m)
                out[i, keep] = row_loglik(data, wi[keep], self.model, of=wi.shape[0])
            else:
                out[i] = row_loglik(data, wi, self.model)
        return out


class TemperedSMC:
    """Adaptive-tempering SMC over ``rows`` × ``trials`` chains; iterate it, or call ``run()``."""

    def __init__(
        self,
        rows: Sequence[Row],
        *,
        trials: int,
        model: FusionModel,
        params: SMCParams,
        rng: np.random.Generator,
    ) -> None:
        if not rows:
            raise ValueError("no rows to sample")
        self.model, self.params, self.rng = model, params, rng
        self.rows_n = len(rows)
        self.trials = trials
        n = max(r.size for r in rows)
        self.n = n
        self.steps = np.repeat(np.array([r.steps for r in rows], dtype=np.float64), trials)
        size = np.repeat(np.array([r.size for r in rows]), trials)
        self.mask = np.arange(n)[None, :] < size[:, None]  # (C, n)
        self.data = _Rows(rows, model)
        c, m = len(self.steps), params.particles
        self.logw = sample_prior((c, m), self.mask[:, None, :], model, rng)
        self.ll = self._loglik(self.logw, np.ones(c, dtype=bool))
        self.beta = np.zeros(c)
        self.scale = np.full(c, 2.38 / math.sqrt(max(1, n - 1)))
        self.final_done = np.zeros(c, dtype=np.int64)
        self.log_evidence = np.zeros(c)
        self.accepted = np.zeros(c)
        self.proposed = np.zeros(c)
        self.iterations = 0
        self.first_beta = np.zeros(c)  # each chain's first temperature above 0 (for ``progress``)

    # ------------------------------------------------------------------ the model, batched

    def _loglik(self, logw: np.ndarray, active: np.ndarray) -> np.ndarray:
        """Marginal log-likelihood ``(C, M)`` of every particle (0 for inactive chains)."""
        c, m, n = logw.shape
        k = self.trials
        w = np.exp(logw).reshape(self.rows_n, k * m, n)
        chains = active.reshape(self.rows_n, k)
        act_rows = np.asarray(chains.any(axis=1))
        ll = self.data.loglik(w, act_rows, chains).reshape(c, m)
        return np.where(active[:, None], ll, 0.0)

    # ------------------------------------------------------------------ the algorithm

    @property
    def done(self) -> bool:
        return bool((self.final_done >= self.params.final_moves).all())

    @property
    def progress(self) -> float:
        """The share of the pass done, in ``[0, 1]``, growing about linearly with the time it takes.

        Per chain: 0.8 for tempering, measured in ``log β`` from its first step ``β₁`` (adaptive
        tempering at a fixed ESS moves ``log β`` by about the same amount each iteration, so the
        first step is taken as one unit of ``1 + ln(1/β₁)``), and 0.2 for the final moves at
        ``β = 1``. Chains are weighted by their row's steps (what an iteration costs them).
        """
        if self.done:
            return 1.0
        b1 = np.where(self.first_beta > 0.0, self.first_beta, 1.0)
        with np.errstate(divide="ignore"):
            lb = np.log(np.maximum(self.beta, 1e-300))
        units = 1.0 + np.log(1.0 / np.minimum(b1, 1.0))
        temper = np.where(
            self.beta >= 1.0,
            1.0,
            np.where(self.beta > 0.0, np.clip((1.0 + lb - np.log(b1)) / units, 0.0, 1.0), 0.0),
        )
        final = np.minimum(self.final_done, self.params.final_moves) / max(1, self.params.final_moves)
        chain = 0.8 * temper + 0.2 * final
        return float(min(1.0, (chain * self.steps).sum() / max(float(self.steps.sum()), 1e-12)))

    def __iter__(self) -> Iterator[TemperedSMC]:
        return self

    def __next__(self) -> TemperedSMC:
        if self.done or self.iterations >= self.params.max_iterations:
            raise StopIteration
        active = self.final_done < self.params.final_moves
        delta = self._next_delta(active)
        inc = delta[:, None] * self.ll
        self.log_evidence += np.where(active, logsumexp_last(inc) - math.log(inc.shape[1]), 0.0)
        idx = resample(inc, self.rng)
        self.logw = gather(self.logw, idx)
        self.ll = gather(self.ll, idx)
        self.beta = np.where(active, np.minimum(1.0, self.beta + delta), self.beta)
        self.beta[self.beta > 1.0 - 1e-12] = 1.0
        self.first_beta = np.where(self.first_beta > 0.0, self.first_beta, self.beta)
        for _ in range(self.params.moves):
            self._move(active & (self.final_done < self.params.final_moves))
            self.final_done += (self.beta >= 1.0) & active
        self.iterations += 1
        return self

    def run(self) -> SMCResult:
        for _ in self:
            pass
        return self.result()

    def result(self) -> SMCResult:
        """Where the chains are now (after the last iteration: the posterior draws)."""
        return SMCResult(
            self.logw,
            self.mask,
            self.log_evidence,
            self.iterations,
            self.accepted / np.maximum(self.proposed, 1.0),
        )

    def _next_delta(self, active: np.ndarray) -> np.ndarray:
        """Per chain the temperature increment that brings the ESS to the target (bisection)."""
        target = self.params.ess_target * self.ll.shape[1]
        room = np.where(active, 1.0 - self.beta, 0.0)
        if NEXT_DELTA.ready():
            return np.asarray(NEXT_DELTA(np.ascontiguousarray(self.ll), room, float(target)))
        return next_delta_reference(self.ll, room, target)

    def _move(self, active: np.ndarray) -> None:
        """One random-walk Metropolis step in additive-log-ratio coordinates for active chains."""
        if not active.any():
            return
        c, m, n = self.logw.shape
        compiled = n <= 128 and MOVE_FRAME.ready() and MOVE_PROPOSE.ready()
        if compiled:
            ref, y, cov = MOVE_FRAME(self.logw, self.mask, active)
        else:
            ref, y, cov = move_frame_reference(self.logw, self.mask)
        chol = np.linalg.cholesky(cov)
        z = self.rng.standard_normal((c, m, n))
        if compiled:
            logw_new, prior, prior_new = MOVE_PROPOSE(
                y, self.logw, self.mask, ref, chol, z, self.scale, float(self.model.alpha), active
            )
        else:
            logw_new, prior, prior_new = move_propose_reference(
                y, self.logw, self.mask, ref, chol, z, self.scale, self.model.alpha
            )
        ll_new = self._loglik(logw_new, active)
        log_a = self.beta[:, None] * (ll_new - self.ll) + prior_new - prior
        acc = (np.log(self.rng.uniform(0.0, 1.0, (c, m))) < log_a) & active[:, None]
        self.logw = np.where(acc[:, :, None], logw_new, self.logw)
        self.ll = np.where(acc, ll_new, self.ll)
        rate = acc.mean(axis=1)
        self.accepted += np.where(active, rate, 0.0)
        self.proposed += active
        # tune the proposal scale toward an acceptance of about 0.3 (higher in 1-D)
        self.scale = np.where(active, self.scale * np.exp(rate - 0.3), self.scale)
