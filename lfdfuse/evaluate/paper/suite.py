"""The report's experiments: styles, junctions, the three-goal task, trials, obstacles.

:func:`run_experiments` is an iterator of :class:`ExperimentEvent` (the CLI turns them into a
progress bar); its last event carries the :class:`~lfdfuse.evaluate.paper.records.PaperResults`.
The experiments are cells (:mod:`~lfdfuse.evaluate.paper.cells`) — every demonstration
learned, every run of a learned network, the trials' relearning — handed to an executor
(:mod:`lfdfuse.parallel`: in this process by default, Dask when asked) in one batch
(:func:`plan_cells`): a run waits only for the table it drives, the relearning only for the
three-goal demo, and the longest chain (that demo, then its 30-trial relearning) starts first.
The logs and tables behind every number are written to the options' ``logs`` folder.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.errors import LfdError
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.evaluate.paper import experiments as ex
from lfdfuse.evaluate.paper.cells import LearnCell, RelearnCell, RunCell, call
from lfdfuse.evaluate.paper.compare import style_errors
from lfdfuse.evaluate.paper.records import STYLES, Learned, PaperResults, PaperRun, junction_choice
from lfdfuse.parallel import Batch, Executor, InProcess
from lfdfuse.sources.tasks import Leg

#: the most a grid is scaled (``--scale``)
MAX_SCALE = 100


@dataclass(frozen=True)
class PaperOptions:
    """``quick``: shorter demonstrations and runs, fewer starts and trials (a smoke test, ~30 s).

    ``scale``: the stochastic cells' runs times ``scale`` — the three-goal task from ``6 × scale``
    starts, obstacle passing ``3 × scale`` runs per controller — for rates with tighter intervals.
    """

    logs: Path
    seed: int = 1
    quick: bool = False
    scale: int = 1

    @property
    def trials(self) -> int:
        return 2 if self.quick else 30

    def estimate(self, trials: int = 1) -> EstimateOptions:
        """The default estimator (pf); fewer particles in quick mode."""
        smc = SMCParams(particles=96) if self.quick else SMCParams()
        return EstimateOptions(trials=trials, seed=self.seed, smc=smc)

    @property
    def task_starts(self) -> int:
        return (2 if self.quick else 6) * self.scale

    @property
    def obstacle_runs(self) -> int:
        return (1 if self.quick else 3) * self.scale

    @property
    def tour_s(self) -> float:
        return 150.0 if self.quick else 300.0


@dataclass(frozen=True)
class ExperimentEvent:
    """Progress: ``done`` of ``total`` cells, the one that just finished, how many are running;
    ``results`` on the last event."""

    done: int
    total: int
    label: str
    results: PaperResults | None = None
    running: int = 0


def _learn_cells(opts: PaperOptions) -> list[LearnCell]:
    cells = [
        LearnCell(
            style,
            opts.logs,
            "tee",
            (Leg(None, style),),
            f"{style}-tee",
            opts.tour_s,
            opts.seed,
            opts.estimate(),
        )
        for style in STYLES
    ]
    cells.append(
        LearnCell(
            "task", opts.logs, "building", ex.THREE_GOALS, "three-goals", 400.0, opts.seed, opts.estimate()
        )
    )
    for style in ("pass-left", "pass-right"):
        secs = 110.0 if opts.quick else 220.0
        cells.append(
            LearnCell(
                style,
                opts.logs,
                "obstacles",
                (Leg(None, style),),
                f"{style}-obstacles",
                secs,
                opts.seed,
                opts.estimate(),
            )
        )
    return cells


def _run_cells(opts: PaperOptions, tables: dict[str, Path]) -> list[RunCell]:
    """Every run, in the order the runs are reported (the starts drawn here, from the seed);
    ``tables``: the learned table of each learn cell's key."""
    logs, cells = opts.logs, []
    starts = ex.BUILDING_STARTS[:1] if opts.quick else ex.BUILDING_STARTS
    secs = 40.0 if opts.quick else 90.0
    for style in STYLES:
        table = tables[style]
        cells.append(RunCell(f"{style}/tee", logs, table, "tee", None, 2 * secs, f"{style}-run-tee", style))
        cells += [
            RunCell(
                f"{style}/building",
                logs,
                table,
                "building",
                start,
                secs,
                f"{style}-run-building-{j}",
                f"{style} from ({start[0]:g}, {start[1]:g})",
            )
            for j, start in enumerate(starts)
        ]
    for style in STYLES:
        for which, start in (("T", ex.T_JUNCTION), ("rotated T", ex.ROTATED_T)):
            tag = "t" if which == "T" else "rt"
            cells.append(
                RunCell(
                    f"junction/{which}",
                    logs,
                    tables[style],
                    "building",
                    start,
                    40.0,
                    f"{style}-{tag}",
                    style,
                )
            )
    rng = np.random.default_rng(opts.seed)
    for k in range(opts.task_starts):
        # near the demonstration's start, but not the same (paper Section V-B.1)
        start = (4.0 + rng.uniform(-1.0, 1.0), 1.2 + rng.uniform(-0.35, 0.35), rng.uniform(-0.35, 0.35))
        start = (float(start[0]), float(start[1]), float(start[2]))
        cells.append(
            RunCell(
                "task",
                logs,
                tables["task"],
                "building",
                start,
                300.0,
                f"three-goals-run-{k}",
                f"run {k + 1}",
                k,
            )
        )
    rng = np.random.default_rng(opts.seed + 1000)
    for style in ("pass-left", "pass-right"):
        for k in range(opts.obstacle_runs):
            start = (1.0, float(1.5 + rng.uniform(-0.3, 0.3)), float(rng.uniform(-0.2, 0.2)))
            cells.append(
                RunCell(
                    style,
                    logs,
                    tables[style],
                    "obstacles",
                    start,
                    90.0,
                    f"{style}-run-{k}",
                    f"{style} run {k + 1}",
                    k,
                )
            )
    return cells


Cell = LearnCell | RunCell | RelearnCell


@dataclass(frozen=True)
class Plan:
    """Every cell of the report in the order its results are reported, and the cells each waits
    for (``after``: the learn cell that writes what it reads)."""

    cells: tuple[Cell, ...]
    after: tuple[tuple[int, ...], ...]

    @property
    def costs(self) -> tuple[float, ...]:
        return tuple(c.cost for c in self.cells)


def plan_cells(opts: PaperOptions) -> Plan:
    """The learn cells, the runs, the trials' relearning; each run after the learn of its table,
    the relearning after the three-goal demo's learn, nothing after anything else."""
    learns = _learn_cells(opts)
    runs = _run_cells(opts, {c.key: c.table for c in learns})
    task = next(c for c in learns if c.key == "task")
    out = opts.logs / f"three-goals-{opts.trials}trials.yaml"
    relearn = RelearnCell("trials", task.segmented, opts.estimate(opts.trials), out, task.seconds)
    writes = {c.table: i for i, c in enumerate(learns)}
    after = [()] * len(learns) + [(writes[r.table],) for r in runs] + [(learns.index(task),)]
    return Plan((*learns, *runs, relearn), tuple(after))


def run_experiments(opts: PaperOptions, *, executor: Executor | None = None) -> Iterator[ExperimentEvent]:
    """Run every experiment on ``executor`` (default: in this process); yields progress, the last
    event with the results. A failed cell fails the report (one line naming the cell)."""
    if not 1 <= opts.scale <= MAX_SCALE:
        raise LfdError(f"--scale must be from 1 to {MAX_SCALE}, got {opts.scale}")
    for folder in (opts.logs, *opts.logs.parents):
        if folder.exists() and not folder.is_dir():
            raise LfdError(f"cannot write the experiments' logs into {folder}: it is a file")
    try:
        opts.logs.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise LfdError(f"cannot create {opts.logs}: {exc.strerror}") from exc
    opts = replace(opts, logs=opts.logs.absolute())  # a worker's working folder may be another
    plan = plan_cells(opts)
    batch: Batch[Cell, Any, list[Any]] = Batch(
        call,
        plan.cells,
        executor=executor or InProcess(),
        reduce=lambda outs: [o.value for o in outs],
        labels=[c.title for c in plan.cells],
        after=plan.after,
        costs=plan.costs,
    )
    total = len(plan.cells)
    yield ExperimentEvent(0, total, "demonstrate and learn")
    for ev in batch:
        if ev.error is not None:
            raise LfdError(f"report: {ev.label}: {ev.error}")
        if ev.index >= 0:
            yield ExperimentEvent(ev.finished, total, ev.label, running=ev.running)
    learned: dict[str, Learned] = {}
    runs: dict[str, list[PaperRun]] = {}
    for cell, value in zip(plan.cells, batch.result(), strict=True):
        if isinstance(cell, LearnCell):
            learned[cell.key] = value
        elif isinstance(cell, RunCell):
            runs.setdefault(cell.key, []).append(value)
        else:
            learned["trials"] = replace(learned["task"], table_path=cell.out, table=value)
    junctions = {
        style: {
            which: junction_choice(runs[f"junction/{which}"][i].pose[-1], which)
            for which in ("T", "rotated T")
        }
        for i, style in enumerate(STYLES)
    }
    order = [*STYLES, "task", "trials", "pass-left", "pass-right"]
    learned = {k: learned[k] for k in order}
    frozen = {k: tuple(v) for k, v in runs.items()}
    results = PaperResults(
        opts.seed, opts.quick, opts.trials, learned, frozen, junctions, tuple(style_errors(learned, frozen))
    )
    yield ExperimentEvent(total, total, "done", results)
