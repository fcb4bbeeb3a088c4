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

How people command: the ``discrete`` command model
---------------------------------------------------

The model above (``continuous``) reads each step's command through the inverse of the drive
mapping: right for a scripted teacher, whose commands lie on that curve. A person at a keyboard
(or at Foxglove's Teleop panel) has a handful of commands — turn in place left, arc left,
straight, arc right, turn in place right — and holds each until the next press. For such a demo
(``--commands discrete``) the observation is *which command the person chose*, at each decision:

* **the command set** is the commands the demo actually holds that move forward or turn, and
  their mirror images, each standing for the heading the drive mapping gives it (an arc
  ``(0.4, 1.0)`` ≈ 38°, a turn in place ≈ 90° or the saturation angle, whichever is larger),
  sorted by that heading. A keyboard or a teleop panel offers both sides: a person who turned
  only right still had the left keys, and not pressing them is evidence too. (On the Neato
  log, which holds forward and turn-in-place-right only, without the mirror the forward bin
  would reach from −45° round to +180° and the learned fusion point backwards: 51° held-out
  error against 27° with it);
* **bins**: the person picks the command nearest to where the fused vector points, so command
  ``c``'s bin is ``[b_c, b_{c+1})`` between the midpoints of neighbouring headings, the outer bins
  reaching to ±π — turning in place means "beyond the arcs", in its direction;
* **nudges**: a press of ``c`` away from ``c₀`` undone (``c₀`` pressed again) within ``nudge_s``
  is a nudge, not a change of mind: the person wanted a heading *between* the two commands and
  held ``c`` for part of the time (a tap of an arc key against a drift — on the TurtleBot log
  most arc presses last 0.12–0.4 s). A nudge observes the interval between ``c₀``'s and ``c``'s
  headings instead of ``c``'s bin; the press back to ``c₀`` is a decision of its own. Below,
  ``bin(c_d)`` is that interval at a nudge. (On the TurtleBot log, sampler settled, nudges
  bring the held-out error from 15.3° to 14.7° and the oracle's from 11.8° to 11.3°: the model
  explains the held-out steps better too; dropping the press back, or narrowing the interval by
  the time held, is worse);
* **likelihood** of the observed command ``c_d`` at decision ``d``: the probability that the
  noisy fused heading ``φ_d + ε`` falls in its bin, ``ε`` von Mises with concentration ``κ``
  (``σ = 1/√κ`` log-uniform between ``discrete_sigma_min_deg`` and ``sigma_max_deg``, integrated
  out on ``discrete_kappa_points`` nodes), mixed with a lapse ``λ`` (a press uniformly among the
  ``m`` commands: a slip of the finger or the safety reflex cannot pull the weights far):
  ``p(c_d | w, κ) = (1 − λ) P_κ(φ_d + ε ∈ bin(c_d)) + λ / m``; a zero fused vector puts the
  heading anywhere (``P = bin width / 2π``);
* **decisions, not ticks**: a decision is a step where the held command changes (a press), or
  where the robot starts moving again after a stop or reverse; while a command is held the person
  decides again every ``recheck_s`` seconds (looking and keeping the key is a decision too, at the
  pace a person re-checks, not at the log's rate). The decisions depend only on the held command
  over time: a log repeating the held command at 4 Hz and one sending it on key change give the
  same decisions and the same posterior. Stops and reversing are counted (for
  ``command_accuracy``) but carry no heading: the primitives steer a forward-moving robot.

The prior on ``w`` is the same Dirichlet. The SMC sampler needs only ``log p(data | w)`` per
particle (:func:`row_loglik`), so both command models share it. A discrete row of few decisions
has a broad, flat-topped posterior (bins) whose mean settles slowly: a pass of such rows (at most
``SMCParams.discrete_few`` decisions) is sampled with ``SMCParams.discrete_factor`` times the
particles (on the TurtleBot log the held-out command accuracy flipped between 9 and 10 of 21 with
the seed at 384 particles, and held at 10 over six seeds at 4 × 384).

Alternatives the held-out error does not favour (the TurtleBot and Neato keyboard logs,
``lfdfuse evaluate LOG.seg.mcap --holdout 0.3``): a *persistence* term (a kept key explained by a
chance of keeping it), *hysteresis* (a kept key's bin widened), *learned bin edges*, and other
readings of a held turn in place (counted once without re-checks, re-checks observing only its
side, all its decisions weighing one, re-checks per angle turned, or observing the rotation left
until the release). With this model the fused error is 14.7° on the TurtleBot (oracle 11.3°)
and 27.2° on the Neato (oracle 4.3°); leaving out any one of the TurtleBot's 40 training
decisions moves its error between 14.4° and 17.2°, so its 3.4° above the oracle is within what
one decision moves, and none of the alternatives brings the Neato within 3° of its oracle.

The person model chosen by the data (options, off by default)
-------------------------------------------------------------

* **the command model by cross-validated prediction** (``EstimateOptions.select_model``,
  :mod:`lfdfuse.estimate.person`): instead of counting distinct commands, the demo's informative
  decisions are cut into 3 contiguous blocks; each candidate — ``continuous``, ``discrete`` with
  lapse ``λ = 0.02``, ``discrete`` with ``λ = 0.2`` — is fitted on two and predicts the third's
  headings (a step whose row the fit never met: straight ahead); the least mean absolute error
  wins, and the choice with every candidate's error goes in ``estimated_by.person_model``. With
  several demos the first one chooses;
* **a hierarchical prior** for a discrete demo's rows (``FusionModel.hierarchy``,
  :mod:`lfdfuse.estimate.hierarchy`): a row's prior is ``Dirichlet(α + c·m)``, ``m`` its goal
  segment's weights (one weight vector fitted to all the segment's decisions) over the row's
  behaviours, ``c`` chosen by evidence over the rows the data does not pin, such a row's
  posterior by likelihood-weighted draws of that prior; pinned rows are unchanged.

Measured on the 13 human drives of ``../shared/realdata`` (``evaluate``'s blocked 5-fold, 10 of
them scored, the fused heading read as it is): the flat prior gives a mean fused error of 31.5°,
fused ≤ 'straight' on 3 of 10, key accuracy ≥ 'straight''s on 7 of 9, fused − oracle median 7.1°.
The hierarchical prior made it worse whatever the range of ``c`` (32.8° with ``c`` up to 128,
32.6° up to 8; keys 6 of 9; the centre is fitted on the rows' own decisions, so the evidence
always favours pooling, and one log lost 8–10°); a lapse of 0.2 for every demo gave 31.7°.
Choosing the command model by cross-validation gave 31.4° (per log −3.6° to +2.1°, fused ≤
'straight' still on 3 of 10; the gamepad drive chose discrete and lost 1.4°): no better than
the count within the noise of so few logs, at about ten sampler passes per fit. Neither is the default.

Reading a fitted table as key presses (``evaluate`` on a discrete demo)
-----------------------------------------------------------------------

Its predictions are key presses (:mod:`lfdfuse.estimate.keys`): the heading of the key whose bin
holds the fused heading (the model's median) and the key most probable by the key shares and ``κ``
fitted on the training decisions. On the 13 human drives fused ≤ 'straight' on 3 → 6 of 10, key
accuracy ≥ 'straight''s on 7 → 8 of 9 (the measurements and what was dropped: ``keys.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.special import i0e, logsumexp

from lfdfuse.estimate import kernels
from lfdfuse.estimate.discrete_kernels import (
    CDF_GRID,
    DISCRETE_BLOCK,
    discrete_log_marginal_reference,
    discrete_loglik,
)
from lfdfuse.estimate.kernels import LOG_MARGINAL, SUM_COS, logsumexp_last, sum_cos_reference


@dataclass(frozen=True)
class FusionModel:
    """Prior and noise model of a fusion row (see the module docstring)."""

    alpha: float = 0.5  # Dirichlet concentration of every weight (see the module docstring)
    sigma_min_deg: float = 0.5  # range of the log-uniform prior on the heading noise σ = 1/√κ
    sigma_max_deg: float = 90.0
    kappa_points: int = 48  # quadrature nodes for integrating κ out
    #: the discrete command model (see the module docstring)
    discrete_sigma_min_deg: float = 2.0
    discrete_kappa_points: int = 16
    lapse: float = 0.02
    recheck_s: float | None = 1.0  # a held command is decided again this often (None: only presses)
    nudge_s: float | None = 1.0  # a press undone within this long is a nudge (None: no nudges)
    #: a discrete demo's rows: the prior centred on their step's weights, its strength learned
    #: from the demo (:mod:`lfdfuse.estimate.hierarchy`); False: the flat Dirichlet(α)
    hierarchy: bool = False

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

    @cached_property
    def discrete_kappas(self) -> np.ndarray:
        """Nodes ``(J,)`` of ``κ`` of the discrete model, equally spaced in ``log σ``."""
        sig = np.radians(
            np.geomspace(self.sigma_max_deg, self.discrete_sigma_min_deg, self.discrete_kappa_points)
        )
        return np.asarray(1.0 / sig**2)

    @cached_property
    def vm_cdf(self) -> np.ndarray:
        """The von Mises CDF ``(J, G + 1)`` of each discrete ``κ`` node on a grid of ``[−π, π]``."""
        x = np.linspace(-math.pi, math.pi, CDF_GRID + 1)
        dens = np.exp(self.discrete_kappas[:, None] * (np.cos(x)[None, :] - 1.0))
        c = np.concatenate(
            [np.zeros((len(dens), 1)), np.cumsum(0.5 * (dens[:, 1:] + dens[:, :-1]), axis=1)], axis=1
        )
        return np.asarray(c / c[:, -1:])

    @cached_property
    def vm_cdf_rows(self) -> np.ndarray:
        """:attr:`vm_cdf` transposed ``(G + 1, J)``, contiguous (the likelihood's lookup table)."""
        return np.ascontiguousarray(self.vm_cdf.T)


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


@dataclass(frozen=True)
class CommandBins:
    """A discrete command set: the heading each command stands for, ascending, and their bins.

    >>> b = CommandBins.from_headings([0.0, 0.66, -0.66, 1.57, -1.57])
    >>> [round(float(e), 2) for e in b.edges]
    [-3.14, -1.11, -0.33, 0.33, 1.11, 3.14]
    >>> b.index(np.array([0.66, 1.57, 0.0])).tolist()
    [3, 4, 2]
    """

    headings: tuple[float, ...]

    @classmethod
    def from_headings(
        cls, headings: np.ndarray | list[float], merge_rad: float = math.radians(0.5)
    ) -> CommandBins:
        h = np.sort(np.asarray(headings, dtype=np.float64).ravel())
        keep: list[float] = []
        for x in h.tolist():
            if not keep or x - keep[-1] > merge_rad:
                keep.append(x)
        return cls(tuple(keep))

    @property
    def size(self) -> int:
        return len(self.headings)

    @property
    def edges(self) -> np.ndarray:
        """``(m + 1,)`` bin edges from −π to π: midpoints between neighbouring headings."""
        h = np.array(self.headings)
        return np.concatenate([[-math.pi], 0.5 * (h[1:] + h[:-1]), [math.pi]])

    def index(self, heading: np.ndarray) -> np.ndarray:
        """The command whose heading is nearest each of ``heading (…)`` (rad)."""
        h = np.array(self.headings)
        return np.asarray(np.argmin(np.abs(np.asarray(heading)[..., None] - h), axis=-1))

    def bounds_of(self, heading: np.ndarray) -> np.ndarray:
        """The bin ``(T, 2)`` (rad) of the command nearest each of ``heading (T,)``."""
        c = self.index(heading)
        e = self.edges
        return np.stack([e[c], e[c + 1]], axis=-1)

    def mirrored(self) -> CommandBins:
        """The set closed under left ↔ right: every command's heading and its negative.

        >>> [round(h, 2) for h in CommandBins((-1.57, 0.0)).mirrored().headings]
        [-1.57, 0.0, 1.57]
        """
        h = np.array(self.headings)
        return CommandBins.from_headings(np.unique(np.round(np.concatenate([h, -h]), 9)))


@dataclass(frozen=True)
class DiscreteRowData:
    """The decisions of one row: the behaviours' robot-frame components ``vx, vy (T, n)`` and the
    observed command's bin ``lo, hi (T,)`` (rad, ``lo < hi``), out of ``commands`` commands (per
    step ``(T,)`` when pooled demos' command sets differ in size: the lapse is each one's)."""

    vx: np.ndarray
    vy: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    commands: int | np.ndarray

    @property
    def steps(self) -> int:
        return int(self.vx.shape[0])

    @property
    def size(self) -> int:
        return int(self.vx.shape[1])


@dataclass(frozen=True)
class MixedRowData:
    """A pooled row whose demos were commanded both ways (a scripted demo and a person's
    keyboard correction): the continuous demos' steps and the discrete demos' decisions, each
    read by its own model with its own noise integrated out; the likelihood is their product."""

    continuous: RowData
    discrete: DiscreteRowData

    @property
    def steps(self) -> int:
        return self.continuous.steps + self.discrete.steps

    @property
    def size(self) -> int:
        return self.continuous.size


Row = RowData | DiscreteRowData | MixedRowData


def has_decisions(data: Row) -> bool:
    """Whether the row observes discrete commands (all or some of its steps)."""
    return not isinstance(data, RowData)


def make_row(
    vectors: np.ndarray,
    demo: np.ndarray,
    bins: CommandBins | None = None,
    bounds: np.ndarray | None = None,
) -> Row:
    """The row data of either command model: continuous without ``bins``, else discrete, where
    each step observes the heading interval ``bounds (T, 2)`` (rad, ``lo < hi``; see
    :func:`~lfdfuse.estimate.commands.observed_bounds`) or, without them, the bin of the command
    nearest its demonstrated heading."""
    if bins is None:
        return row_data(vectors, demo)
    if bounds is None:
        bounds = bins.bounds_of(np.arctan2(demo[:, 1], demo[:, 0]))
    return DiscreteRowData(
        np.ascontiguousarray(vectors[..., 0]),
        np.ascontiguousarray(vectors[..., 1]),
        np.ascontiguousarray(bounds[:, 0]),
        np.ascontiguousarray(bounds[:, 1]),
        bins.size,
    )


def make_pooled_row(vectors: np.ndarray, demo: np.ndarray, bounds: np.ndarray, commands: np.ndarray) -> Row:
    """The row data of pooled demos that each keep their command model: per step its command
    set's size ``commands (T,)`` (0: a continuous demo's step) and, for a discrete step, the
    heading interval it observes ``bounds (T, 2)`` (rad; ignored where ``commands`` is 0)."""
    cont = commands == 0
    disc = ~cont
    sizes = commands[disc]
    discrete = DiscreteRowData(
        np.ascontiguousarray(vectors[disc][..., 0]),
        np.ascontiguousarray(vectors[disc][..., 1]),
        np.ascontiguousarray(bounds[disc, 0]),
        np.ascontiguousarray(bounds[disc, 1]),
        int(sizes[0]) if len(sizes) and (sizes == sizes[0]).all() else sizes.astype(np.float64),
    )
    if not cont.any():
        return discrete
    continuous = row_data(vectors[cont], demo[cont])
    if not disc.any():
        return continuous
    return MixedRowData(continuous, discrete)


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


def sum_cos(data: RowData, w: np.ndarray, *, of: int | None = None) -> np.ndarray:
    """The sufficient statistic ``S = Σₜ cos Δₜ`` for weight vectors ``w (P, n)`` → ``(P,)``:
    compiled (:mod:`lfdfuse.estimate.kernels`) or :func:`sum_cos_reference`, equal to rounding.
    ``of``: ``w`` is a subset of that many particles (the steps summed in their blocks)."""
    wt = np.ascontiguousarray(w.T, dtype=np.float64)
    block = max(16, kernels.BLOCK_ELEMENTS // max(1, of or w.shape[0]))
    if w.shape[1] and SUM_COS.ready():
        return np.asarray(SUM_COS(data.along, data.across, wt, block, kernels.behaviour_width(w.shape[1])))
    return sum_cos_reference(data, w)


def discrete_log_marginal(data: DiscreteRowData, w: np.ndarray, model: FusionModel) -> np.ndarray:
    """``log p(c₁…c_T | w)`` of the discrete model, ``κ`` integrated out: ``w (P, n)`` → ``(P,)``;
    compiled (:mod:`~lfdfuse.estimate.discrete_kernels`) or its numpy reference, the same numbers."""
    if not DISCRETE_BLOCK.ready():
        return discrete_log_marginal_reference(data, w, model)
    if isinstance(data.commands, np.ndarray):
        lapse = model.lapse / np.maximum(1.0, data.commands)
    else:
        lapse = np.full(data.steps, model.lapse / max(1, data.commands))
    table = model.vm_cdf_rows
    ll = discrete_loglik(
        data.vx, data.vy, data.lo, data.hi, lapse, 1.0 - model.lapse, np.asarray(w, dtype=np.float64), table
    )
    return np.asarray(logsumexp_last(ll) - math.log(table.shape[1]))


def row_loglik(data: Row, w: np.ndarray, model: FusionModel, *, of: int | None = None) -> np.ndarray:
    """``log p(data | w)`` with the noise integrated out, for weights ``w (P, n)`` → ``(P,)``
    (``of``: see :func:`sum_cos`; a continuous row only)."""
    if isinstance(data, DiscreteRowData):
        return discrete_log_marginal(data, w, model)
    if isinstance(data, MixedRowData):
        both = row_loglik(data.continuous, w, model) + discrete_log_marginal(data.discrete, w, model)
        return np.asarray(both)
    if w.shape[1] and SUM_COS.ready() and LOG_MARGINAL.ready():  # compiled, over the cores
        return kernels.continuous_loglik(data, w, of or w.shape[0], model.kappas, model._log_norm)
    return log_marginal(sum_cos(data, w, of=of), data.steps, model)


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
