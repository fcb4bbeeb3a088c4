"""Many logs at once (``lfdfuse evaluate LOG…``): one held-out evaluation per log, and a summary.

Every log is one job on the executor: the worker reads the log itself (its path crosses the
wire, never its arrays) and prepares it on the way when needed — a robot log (a bag, a CARMEN
or BreezySLAM file) is imported, an lfdfuse demo segmented, both into a temporary folder of the
worker — then scores it as for a single log: by blocked k-fold over its decisions
(:func:`~lfdfuse.evaluate.folds.evaluate_folds`, segmented on the way as ``lfdfuse segment``
does, lag ``auto``), or with ``holdout`` by the last part in time
(:func:`~lfdfuse.evaluate.holdout.evaluate`, segmented on the way at lag 0, as before). The
summary says, across the logs that could be evaluated, how often the learned fusion beats each
baseline (with a Wilson 95 % interval of that share) and each method's mean error; for k-fold
also, per rival, the median difference with a bootstrap interval over the logs
(:func:`~lfdfuse.evaluate.corpus.compare`).
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.errors import ConfigError, LfdError, LogError
from lfdfuse.evaluate.cloning import sector_features
from lfdfuse.evaluate.corpus import compare
from lfdfuse.evaluate.folds import FOLDS, evaluate_folds
from lfdfuse.evaluate.holdout import METHODS, Evaluation, evaluate
from lfdfuse.execute.starts import wilson_interval
from lfdfuse.log.reader import file_info
from lfdfuse.parallel import Batch, Executor, Outcome
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented, read_segmented_and_run
from lfdfuse.sources.importers import is_lfdfuse_log
from lfdfuse.sources.importers.convert import import_log

#: the methods fused is compared with in the summary (the oracle is a floor, not a rival)
BASELINES: tuple[str, ...] = tuple(m for m in METHODS if m not in ("fused", "oracle"))


@dataclass(frozen=True)
class LogJob:
    path: str  # as the user gave it (shown, and written to the JSON)
    read: str  # absolute: what the worker opens
    holdout: float | None  # the last part by time; None: blocked k-fold over the decisions
    seed: int
    folds: int = FOLDS


@dataclass(frozen=True)
class LogEvaluation:
    """One log's evaluation and what was done to the log on the way (``import``, ``segment``)."""

    path: str
    prepared: tuple[str, ...]
    evaluation: Evaluation

    def to_dict(self) -> dict[str, Any]:
        return {"path": self.path, "prepared": list(self.prepared), **self.evaluation.to_dict()}


def _kind(path: Path) -> str:
    """``segmented``, ``demo`` (an lfdfuse log without the /lfd channels) or ``robot`` (to import)."""
    if is_lfdfuse_log(path):
        return "segmented" if "/lfd/behaviors" in file_info(path).channels else "demo"
    return "robot"


def evaluate_log(job: LogJob) -> LogEvaluation:
    """Prepare (import, segment) when needed, then evaluate one log; errors name the log."""
    src = Path(job.read)
    if not src.exists():
        raise LogError(f"no such file or folder: {job.path}")
    with tempfile.TemporaryDirectory(prefix="lfdfuse-evaluate-") as tmp:
        try:
            return _prepare_and_evaluate(job, src, Path(tmp))
        except LfdError as exc:
            # the worker's temporary files mean nothing to the user: name the log they gave
            msg = str(exc).replace(f"{tmp}/demo.seg.mcap", job.path).replace(f"{tmp}/demo.mcap", job.path)
            msg = msg.replace(f"{job.path}: {job.path}", job.path)
            raise LfdError(msg if job.path in msg else f"{job.path}: {msg}") from exc


def _score(job: LogJob, seg: Path) -> Evaluation:
    if job.holdout is not None:
        return evaluate(read_segmented(seg), holdout=job.holdout, seed=job.seed)
    run, raw = read_segmented_and_run(seg)
    if not np.array_equal(run.t_ns, raw.t_ns):  # one step per scan, as segment writes them
        raise LogError(f"{seg}: the /lfd/* steps are not the log's scans; segment the demo again")
    features = sector_features(raw.ranges_m, raw.geometry)
    return evaluate_folds(run, folds=job.folds, seed=job.seed, features=features)


def _prepare_and_evaluate(job: LogJob, src: Path, tmp: Path) -> LogEvaluation:
    kind = _kind(src)
    if kind == "segmented":
        return LogEvaluation(job.path, (), _score(job, src))
    prepared: tuple[str, ...] = ("segment",)
    demo = src
    if kind == "robot":
        demo, prepared = tmp / "demo.mcap", ("import", "segment")
        import_log(src, out=demo)
    # k-fold segments as `lfdfuse segment` does by default (the lag that explains the demo
    # best); the time split keeps lag 0, its numbers as they were
    if job.holdout is not None:
        seg = segment_file(demo, out=tmp / "demo.seg.mcap", measure_lag=False)
    else:
        seg = segment_file(demo, out=tmp / "demo.seg.mcap", lag_s=None)
    return LogEvaluation(job.path, prepared, _score(job, Path(seg.out)))


@dataclass(frozen=True)
class LogsResult:
    """Every log's evaluation or error, in the order given, and the summary across logs."""

    rows: tuple[LogEvaluation | tuple[str, str], ...]  # an evaluation, or (path, error)
    seed: int = 0  # of the bootstrap over logs (k-fold's comparisons)

    @property
    def evaluations(self) -> tuple[LogEvaluation, ...]:
        return tuple(r for r in self.rows if isinstance(r, LogEvaluation))

    @property
    def methods(self) -> tuple[str, ...]:
        """The methods every row scores: k-fold's (with ``bc``) or the time split's."""
        evs = self.evaluations
        return tuple(evs[0].evaluation.methods) if evs else METHODS

    @property
    def baselines(self) -> tuple[str, ...]:
        return tuple(m for m in self.methods if m not in ("fused", "oracle"))

    def summary(self) -> dict[str, Any]:
        evs = self.evaluations
        n = len(evs)
        methods = self.methods
        errors = {m: [e.evaluation.methods[m].heading_error_deg for e in evs] for m in methods}

        def mean(xs: list[float]) -> float | None:
            xs = [x for x in xs if math.isfinite(x)]
            return round(sum(xs) / len(xs), 3) if xs else None

        beats = {}
        for b in self.baselines:
            k = sum(f < o for f, o in zip(errors["fused"], errors[b], strict=True))
            lo, hi = wilson_interval(k, n)
            beats[b] = {
                "logs": k,
                "of": n,
                "share": round(k / n, 4) if n else None,
                "ci95": [round(lo, 4), round(hi, 4)],
            }
        out: dict[str, Any] = {
            "logs": n,
            "failed": len(self.rows) - n,
            "mean_heading_error_deg": {m: mean(errors[m]) for m in methods},
            "fused_beats": beats,
        }
        if evs and evs[0].evaluation.split == "kfold":
            out["compare"] = self._compare(methods)
        return out

    def _compare(self, methods: tuple[str, ...]) -> dict[str, Any]:
        """Fused against every other method (the oracle too: the floor) across the logs: heading
        error, turning error, and command accuracy where the logs are discrete."""
        evs = [e.evaluation for e in self.evaluations]

        def col(m: str, what: str) -> list[float | None]:
            return [getattr(ev.methods[m], what) for ev in evs]

        out: dict[str, Any] = {}
        for k, m in enumerate(x for x in methods if x != "fused"):
            seed = self.seed + 7919 * k  # each rival its own resamples, the same on every run
            out[m] = {
                "heading_error_deg": compare(
                    col("fused", "heading_error_deg"), col(m, "heading_error_deg"), seed=seed
                ),
                "turning_error_deg": compare(
                    col("fused", "turning_error_deg"), col(m, "turning_error_deg"), seed=seed
                ),
                "command_accuracy": compare(
                    col("fused", "command_accuracy"),
                    col(m, "command_accuracy"),
                    seed=seed,
                    higher_is_better=True,
                ),
            }
        return out

    def to_dict(self) -> dict[str, Any]:
        logs = [
            r.to_dict() if isinstance(r, LogEvaluation) else {"path": r[0], "error": r[1]} for r in self.rows
        ]
        return {"logs": logs, "summary": self.summary()}


def plan_logs(
    paths: list[Path], *, holdout: float | None, seed: int, folds: int = FOLDS
) -> tuple[LogJob, ...]:
    """One job per path (a bad ``holdout`` or ``folds`` is one error before any job starts)."""
    if holdout is not None and not (math.isfinite(holdout) and 0.0 < holdout < 1.0):
        raise ConfigError(f"--holdout must be a fraction between 0 and 1, got {holdout}")
    if folds < 2:
        raise ConfigError(f"--folds must be at least 2, got {folds}")
    if not paths:
        raise ConfigError("no log to evaluate")
    return tuple(LogJob(str(p), str(p.absolute()), holdout, seed, folds) for p in paths)


def summarise_logs(jobs: tuple[LogJob, ...], outcomes: tuple[Outcome[LogEvaluation], ...]) -> LogsResult:
    rows: list[LogEvaluation | tuple[str, str]] = []
    for job, out in zip(jobs, outcomes, strict=True):
        rows.append(out.value if out.value is not None else (job.path, str(out.error)))
    return LogsResult(tuple(rows), seed=jobs[0].seed if jobs else 0)


def evaluate_logs(
    paths: list[Path],
    *,
    holdout: float | None = None,
    seed: int = 0,
    folds: int = FOLDS,
    executor: Executor,
) -> Batch[LogJob, LogEvaluation, LogsResult]:
    """A batch of one evaluation per log on ``executor``: iterate it for progress, then ``.result()``.
    ``holdout`` scores the last part of each log by time; without it, ``folds`` blocked folds."""
    jobs = plan_logs(paths, holdout=holdout, seed=seed, folds=folds)
    return Batch(
        evaluate_log,
        jobs,
        executor=executor,
        reduce=lambda outs: summarise_logs(jobs, outs),
        labels=[j.path for j in jobs],
    )
