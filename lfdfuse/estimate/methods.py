"""The estimation methods: a :class:`Method` enum and its registry, method → row estimator.

Every method estimates the weights of many *problems* at once — a problem is one group's
``(vectors (T, n, 2), demo (T, 2))`` — and names what it used in the table's provenance
(``estimated_by``). :data:`REGISTRY` holds one :class:`Estimator` per :class:`Method`; adding a
method is adding an enum member and its entry, and nothing falls through to a default branch.

``pf`` samples every problem in one batched tempered SMC pass (:mod:`lfdfuse.estimate.smc`);
``paper`` runs the published particle filter (:mod:`lfdfuse.estimate.paper`) per problem;
``nnls`` and ``arbitration`` are the baselines (:mod:`lfdfuse.estimate.baselines`), with
bootstrap fits as their trials.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from enum import StrEnum
from typing import NamedTuple

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.baselines import arbitration_weights, nnls_weights
from lfdfuse.estimate.identifiability import identifiable
from lfdfuse.estimate.model import (
    CommandBins,
    FusionModel,
    Row,
    has_decisions,
    make_pooled_row,
    make_row,
    row_loglik,
)
from lfdfuse.estimate.paper import Likelihood as LikelihoodName
from lfdfuse.estimate.paper import PFParams, normalise, run_filter
from lfdfuse.estimate.smc import SMCParams, TemperedSMC
from lfdfuse.progress import Progress, part, tell
from lfdfuse.segment.commands import CommandMode


class Problem(NamedTuple):
    """One group's steps: ``vectors (T, n, 2)``, ``demo (T, 2)`` and, for the discrete command
    model, the heading interval each step observes ``bounds (T, 2)`` (None: the bin of the
    demonstrated command; see :func:`~lfdfuse.estimate.model.make_row`). A plain
    ``(vectors, demo)`` pair is a problem too."""

    vectors: np.ndarray
    demo: np.ndarray
    bounds: np.ndarray | None = None
    #: pooled demos that each keep their command model: per step its command set's size (0: a
    #: continuous demo's step; see :func:`~lfdfuse.estimate.model.make_pooled_row`)
    commands: np.ndarray | None = None


class Method(StrEnum):
    """How a group's weights are estimated (``estimate --method``)."""

    #: the exact posterior: Dirichlet prior, von Mises heading noise, tempered SMC
    PF = "pf"
    #: the paper's particle filter as published
    PAPER = "paper"
    #: non-negative least squares on the demonstrated vector
    NNLS = "nnls"
    #: the best single behaviour (arbitration, the paper's foil)
    ARBITRATION = "arbitration"


class Likelihood(StrEnum):
    """The paper filter's likelihood (``estimate --likelihood``)."""

    #: ``2 - D/2`` as published
    PAPER = "paper"
    #: a von Mises density of the heading error
    VONMISES = "vonmises"

    @property
    def literal(self) -> LikelihoodName:
        """The name :class:`~lfdfuse.estimate.paper.PFParams` takes."""
        return self.value


@dataclass(frozen=True)
class EstimateOptions:
    method: Method = Method.PF
    trials: int = 1
    seed: int = 0
    model: FusionModel = field(default_factory=FusionModel)  # pf: prior and noise model
    smc: SMCParams = field(default_factory=SMCParams)  # pf: the sampler
    pf: PFParams = field(default_factory=PFParams)  # paper: the published filter
    min_samples: int = 30  # rows with fewer informative steps are flagged low_samples
    commands: CommandMode = "auto"  # the command model: auto | continuous | discrete (DESIGN §6)
    #: with ``commands`` auto, the command model and lapse chosen by cross-validated prediction
    #: on the demo itself (:mod:`lfdfuse.estimate.person`)
    select_model: bool = False


@dataclass(frozen=True)
class RowEstimate:
    """One group's estimate over its ``n`` applicable behaviours."""

    weights: np.ndarray  # (n,) summing to 1
    std: np.ndarray  # (n,) posterior std (pf), else the spread over trials
    trial_std: np.ndarray | None  # (n,) spread of the trials' estimates, when trials > 1
    identifiable: bool | None  # pf only: False when the prior decides some direction


#: a method's row estimator: ``(problems, options, rng, bins, progress)``; ``bins`` the discrete
#: command model's command set or None; ``progress`` told ``(done, total)`` as rows are sampled
RowsFn = Callable[
    [Sequence[Problem], EstimateOptions, np.random.Generator, CommandBins | None, Progress | None],
    list[RowEstimate],
]


@dataclass(frozen=True)
class Estimator:
    """A method: its row estimator, the provenance entries it adds to the table, what it is in
    a few words (``label``, for help texts and score tables), and whether it fits one point
    (``point_fit``: no posterior, so a std only from bootstrap trials; ``evaluate`` scores the
    point fits as the baselines beside the default estimator)."""

    rows: RowsFn
    provenance: Callable[[EstimateOptions, CommandBins | None], dict[str, object]]
    label: str
    point_fit: bool


#: chains (rows × trials) per sampler pass: bounds the sampler's memory (chains × particles × κ nodes)
CHAIN_BATCH = 128


def _pf_rows(
    problems: Sequence[Problem],
    opts: EstimateOptions,
    rng: np.random.Generator,
    bins: CommandBins | None,
    progress: Progress | None,
) -> list[RowEstimate]:
    """One batched SMC pass over every problem with ≥ 2 behaviours and ≥ 1 step; ``progress``
    in steps sampled (a row's steps × its share of the sampler's pass), every iteration."""
    out: list[RowEstimate | None] = [None] * len(problems)
    todo = []
    for i, p in enumerate(problems):
        vec = p.vectors
        n = vec.shape[1]
        if n == 1:
            out[i] = RowEstimate(np.ones(1), np.zeros(1), np.zeros(1) if opts.trials > 1 else None, True)
        elif vec.shape[0] == 0:  # no data: the prior, which pins nothing
            prior_sd = math.sqrt((n - 1) / (n * n * (n * opts.model.alpha + 1.0)))
            out[i] = RowEstimate(np.full(n, 1.0 / n), np.full(n, prior_sd), None, False)
        else:
            todo.append(i)
    k = opts.trials
    # rows are sampled in batches: the sampler's arrays grow with the rows it holds, and an
    # hour-long demo has hundreds of rows (a batch is one pass for any ordinary demo)
    per_pass = max(1, CHAIN_BATCH // k)
    total = float(sum(problems[i][0].shape[0] for i in todo))
    done = 0.0
    tell(progress, 0.0, total)
    for b in range(0, len(todo), per_pass):
        batch = todo[b : b + per_pass]
        size = float(sum(problems[i].vectors.shape[0] for i in batch))
        datas = [_row_data(problems[i], bins) for i in batch]
        params = opts.smc
        if any(has_decisions(d) for d in datas) and sum(d.steps for d in datas) <= params.discrete_few:
            params = replace(params, particles=params.particles * params.discrete_factor)
        smc = TemperedSMC(datas, trials=k, model=opts.model, params=params, rng=rng)
        for _ in smc:
            tell(progress, done + size * smc.progress, total)
        res = smc.result()
        done += size
        tell(progress, done, total)
        means, covs, particles = res.mean(), res.cov(), res.weights
        for j, i in enumerate(batch):
            n = problems[i].vectors.shape[1]
            cov = covs[j * k : (j + 1) * k, :n, :n].mean(axis=0)
            pinned = identifiable(cov, opts.model)
            if pinned:
                # the data pins the row: report the posterior mode (the most likely posterior
                # particle), which lands as close to the truth as a heading fit; a posterior mean
                # is pulled off the simplex's edges, where sparse rows live, by the posterior's width
                w = particles[j * k : (j + 1) * k, :, :n]  # (K, M, n)
                best = np.array(
                    [trial[int(np.argmax(row_loglik(datas[j], trial, opts.model)))] for trial in w]
                )  # (K, n)
            else:
                # the data leaves a direction open: the posterior mean, where the prior decides it
                best = means[j * k : (j + 1) * k, :n]
            out[i] = RowEstimate(
                normalise(best.mean(axis=0)),
                np.sqrt(np.maximum(np.diag(cov), 0.0)),
                best.std(axis=0) if k > 1 else None,
                pinned,
            )
    return [r for r in out if r is not None]


def _row_data(p: Problem, bins: CommandBins | None) -> Row:
    """The likelihood's data of one problem: its own command models when pooled, else ``bins``'."""
    if p.commands is not None and p.bounds is not None:
        return make_pooled_row(p.vectors, p.demo, p.bounds, p.commands)
    return make_row(p.vectors, p.demo, bins, p.bounds)


def _single(k: int) -> RowEstimate:
    return RowEstimate(np.ones(1), np.zeros(1), np.zeros(1) if k > 1 else None, None)


def _paper_rows(
    problems: Sequence[Problem],
    opts: EstimateOptions,
    rng: np.random.Generator,
    bins: CommandBins | None,
    progress: Progress | None,
) -> list[RowEstimate]:
    """The published filter per problem; ``progress`` in filter updates."""
    out = []
    k = opts.trials
    # a filter makes max(T, min_updates) updates at least (short groups are passed over again)
    cost = [
        0.0 if p.vectors.shape[1] == 1 else float(max(p.vectors.shape[0], opts.pf.min_updates, 1))
        for p in problems
    ]
    total, done = sum(cost), 0.0
    tell(progress, 0.0, total)
    for (vectors, demo, *_), c in zip(problems, cost, strict=True):
        if vectors.shape[1] == 1:
            out.append(_single(k))
            continue
        sub = part(progress, start=done, size=c, total=total)
        res = run_filter(vectors, demo, trials=k, rng=rng, params=opts.pf, progress=sub)
        done += c
        spread = res.weights.std(axis=0) if k > 1 else None
        out.append(RowEstimate(normalise(res.weights.mean(axis=0)), res.spread.mean(axis=0), spread, None))
    return out


def _fit_rows(fit: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> RowsFn:
    """A heading fit per problem; ``trials > 1``: the mean and spread of bootstrap fits;
    ``progress`` in steps fitted, per row."""

    def rows(
        problems: Sequence[Problem],
        opts: EstimateOptions,
        rng: np.random.Generator,
        bins: CommandBins | None,
        progress: Progress | None,
    ) -> list[RowEstimate]:
        out = []
        k = opts.trials
        total, done = float(sum(p.vectors.shape[0] for p in problems)), 0.0
        tell(progress, 0.0, total)
        for vectors, demo, *_ in problems:
            t, n, _ = vectors.shape
            if n == 1:
                out.append(_single(k))
            elif k == 1:
                out.append(RowEstimate(normalise(fit(vectors, demo)), np.zeros(n), None, None))
            else:
                boots = np.array(
                    [
                        normalise(fit(vectors[idx], demo[idx]))
                        for idx in (rng.integers(0, t, t) for _ in range(k))
                    ]
                )
                out.append(
                    RowEstimate(normalise(boots.mean(axis=0)), boots.std(axis=0), boots.std(axis=0), None)
                )
            done += t
            tell(progress, done, total)
        return out

    return rows


def _pf_provenance(opts: EstimateOptions, bins: CommandBins | None) -> dict[str, object]:
    noise = (
        "vonmises, kappa marginalised"
        if bins is None
        else f"vonmises heading in {bins.size} command bins, kappa marginalised, lapse {opts.model.lapse:g}"
    )
    return {"particles": opts.smc.particles, "prior": f"dirichlet({opts.model.alpha:g})", "noise": noise}


def _paper_provenance(opts: EstimateOptions, bins: CommandBins | None) -> dict[str, object]:
    return {"particles": opts.pf.particles, "likelihood": opts.pf.likelihood}


def _none(opts: EstimateOptions, bins: CommandBins | None) -> dict[str, object]:
    return {}


REGISTRY: dict[Method, Estimator] = {
    Method.PF: Estimator(
        _pf_rows,
        _pf_provenance,
        "exact posterior: Dirichlet prior, von Mises heading noise, tempered SMC",
        point_fit=False,
    ),
    Method.PAPER: Estimator(
        _paper_rows, _paper_provenance, "the paper's particle filter as published", point_fit=False
    ),
    Method.NNLS: Estimator(_fit_rows(nnls_weights), _none, "non-negative least squares", point_fit=True),
    Method.ARBITRATION: Estimator(
        _fit_rows(arbitration_weights), _none, "best single behaviour per BAC", point_fit=True
    ),
}

#: the methods that fit one point, in :class:`Method` order (the baselines ``evaluate`` scores)
POINT_FITS: tuple[Method, ...] = tuple(m for m in Method if REGISTRY[m].point_fit)


def is_point_fit(name: object) -> bool:
    """Whether the method a table names (its ``estimated_by.method``) fits one point; False for a
    name no method has (a hand-written table may say anything)."""
    return any(name == m.value for m in POINT_FITS)


def method_of(value: Method | str) -> Method:
    """The :class:`Method` named ``value``; a :class:`ConfigError` naming the valid ones otherwise."""
    try:
        return Method(value)
    except ValueError:
        valid = ", ".join(m.value for m in Method)
        raise ConfigError(f"unknown method {str(value)[:40]!r} (valid: {valid})") from None


def estimator(value: Method | str) -> Estimator:
    return REGISTRY[method_of(value)]


def check_options(opts: EstimateOptions) -> None:
    """A :class:`ConfigError` for an unknown method or a count below 1."""
    method_of(opts.method)
    if opts.trials < 1 or opts.pf.particles < 1 or opts.smc.particles < 1:
        raise ConfigError("--trials and --particles must be at least 1")


def estimate_groups(
    problems: Sequence[Problem | tuple[np.ndarray, np.ndarray]],
    *,
    opts: EstimateOptions,
    rng: np.random.Generator,
    bins: CommandBins | None = None,
    progress: Progress | None = None,
) -> list[RowEstimate]:
    """Estimates for groups given as :class:`Problem` s or ``(vectors (T, n, 2), demo (T, 2))``
    pairs, in order (``bins``: the discrete command model's command set; only ``pf`` models it).
    ``progress`` is told ``(done, total)`` as the work goes (many times for a long pass), ending
    at ``total``."""
    out = estimator(opts.method).rows([Problem(*p) for p in problems], opts, rng, bins, progress)
    tell(progress, 1.0, 1.0)
    return out


def estimate_group(
    vectors: np.ndarray, demo: np.ndarray, *, opts: EstimateOptions, rng: np.random.Generator
) -> RowEstimate:
    """The estimate of one group: ``vectors (T, n, 2)``, ``demo (T, 2)``."""
    return estimate_groups([(vectors, demo)], opts=opts, rng=rng)[0]


def provenance(
    opts: EstimateOptions,
    *,
    source: str,
    commands: str | None = None,
    lag_s: str | None = None,
    bins: CommandBins | None = None,
) -> dict[str, object]:
    """The table's ``estimated_by``: method, trials, seed, source, and the method's own entries."""
    method = method_of(opts.method)
    by: dict[str, object] = {
        "method": method.value,
        "trials": opts.trials,
        "seed": opts.seed,
        "source": source,
    }
    if commands is not None:
        by["commands"] = commands
    if lag_s is not None:  # the lag segment paired commands with (``segment_lag_s``)
        by["lag_s"] = lag_s
    return by | REGISTRY[method].provenance(opts, bins)
