"""Many logs at once (``lfdfuse evaluate LOG…``): one held-out evaluation per log, and a summary.

Every log is one job on the executor: the worker reads the log itself (its path crosses the
wire, never its arrays) and prepares it on the way when needed — a robot log (a bag, a CARMEN
or BreezySLAM file) is imported, an lfdfuse demo segmented, both into a temporary folder of the
worker — then :func:`~lfdfuse.evaluate.holdout.evaluate` scores it as for a single log. The
summary says, across the logs that could be evaluated, how often the learned fusion beats each
baseline (with a Wilson 95 % interval of that share) and each method's mean error.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lfdfuse.errors import ConfigError, LfdError, LogError
from lfdfuse.evaluate.holdout import METHODS, Evaluation, evaluate
from lfdfuse.execute.starts import wilson_interval
from lfdfuse.log.reader import file_info
from lfdfuse.parallel import Batch, Executor, Outcome
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from lfdfuse.sources.importers import is_lfdfuse_log
from lfdfuse.sources.importers.convert import import_log

#: the methods fused is compared with in the summary (the oracle is a floor, not a rival)
BASELINES: tuple[str, ...] = tuple(m for m in METHODS if m not in ("fused", "oracle"))


@dataclass(frozen=True)
class LogJob:
    path: str  # as the user gave it (shown, and written to the JSON)
    read: str  # absolute: what the worker opens
    holdout: float
    seed: int


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


def _prepare_and_evaluate(job: LogJob, src: Path, tmp: Path) -> LogEvaluation:
    kind = _kind(src)
    if kind == "segmented":
        return LogEvaluation(job.path, (), evaluate(read_segmented(src), holdout=job.holdout, seed=job.seed))
    prepared: tuple[str, ...] = ("segment",)
    demo = src
    if kind == "robot":
        demo, prepared = tmp / "demo.mcap", ("import", "segment")
        import_log(src, out=demo)
    seg = segment_file(demo, out=tmp / "demo.seg.mcap", measure_lag=False)
    return LogEvaluation(
        job.path, prepared, evaluate(read_segmented(seg.out), holdout=job.holdout, seed=job.seed)
    )


@dataclass(frozen=True)
class LogsResult:
    """Every log's evaluation or error, in the order given, and the summary across logs."""

    rows: tuple[LogEvaluation | tuple[str, str], ...]  # an evaluation, or (path, error)

    @property
    def evaluations(self) -> tuple[LogEvaluation, ...]:
        return tuple(r for r in self.rows if isinstance(r, LogEvaluation))

    def summary(self) -> dict[str, Any]:
        evs = self.evaluations
        n = len(evs)
        errors = {m: [e.evaluation.methods[m].heading_error_deg for e in evs] for m in METHODS}

        def mean(xs: list[float]) -> float | None:
            xs = [x for x in xs if math.isfinite(x)]
            return round(sum(xs) / len(xs), 3) if xs else None

        beats = {}
        for b in BASELINES:
            k = sum(f < o for f, o in zip(errors["fused"], errors[b], strict=True))
            lo, hi = wilson_interval(k, n)
            beats[b] = {
                "logs": k,
                "of": n,
                "share": round(k / n, 4) if n else None,
                "ci95": [round(lo, 4), round(hi, 4)],
            }
        return {
            "logs": n,
            "failed": len(self.rows) - n,
            "mean_heading_error_deg": {m: mean(errors[m]) for m in METHODS},
            "fused_beats": beats,
        }

    def to_dict(self) -> dict[str, Any]:
        logs = [
            r.to_dict() if isinstance(r, LogEvaluation) else {"path": r[0], "error": r[1]} for r in self.rows
        ]
        return {"logs": logs, "summary": self.summary()}


def plan_logs(paths: list[Path], *, holdout: float, seed: int) -> tuple[LogJob, ...]:
    """One job per path (a bad ``holdout`` is one error before any job starts)."""
    if not (math.isfinite(holdout) and 0.0 < holdout < 1.0):
        raise ConfigError(f"--holdout must be a fraction between 0 and 1, got {holdout}")
    if not paths:
        raise ConfigError("no log to evaluate")
    return tuple(LogJob(str(p), str(p.absolute()), holdout, seed) for p in paths)


def summarise_logs(jobs: tuple[LogJob, ...], outcomes: tuple[Outcome[LogEvaluation], ...]) -> LogsResult:
    rows: list[LogEvaluation | tuple[str, str]] = []
    for job, out in zip(jobs, outcomes, strict=True):
        rows.append(out.value if out.value is not None else (job.path, str(out.error)))
    return LogsResult(tuple(rows))


def evaluate_logs(
    paths: list[Path], *, holdout: float = 0.3, seed: int = 0, executor: Executor
) -> Batch[LogJob, LogEvaluation, LogsResult]:
    """A batch of one evaluation per log on ``executor``: iterate it for progress, then ``.result()``."""
    jobs = plan_logs(paths, holdout=holdout, seed=seed)
    return Batch(
        evaluate_log,
        jobs,
        executor=executor,
        reduce=lambda outs: summarise_logs(jobs, outs),
        labels=[j.path for j in jobs],
    )
