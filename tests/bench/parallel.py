"""Many runs at once: serial against a 2-worker Dask ``LocalCluster``, same run, same grid.

First the paper's grid itself (``make paper``: every cell of the report, serial and on the
workers, the report's numbers byte-identical), beside its cost model from the serial run's job
times: ``model_s`` = total / workers, ``bound_s`` = max(that, the costliest chain of jobs that
wait for each other: the three-goal demo, then its 30-trial relearn) and ``schedule_s``, the jobs
list-scheduled in the order the batch hands them out. Then the cost model on a grid of equal jobs,
the paper's Fig. 11 experiment at scale: the three-goal table (learned once from the
shipped sample demo) driven from N perturbed starts (``execute --starts N``), N = 2, 4 and 8
(2, 4, 6 in quick mode, runs of at most 40 s). For each size it measures the wall time in this process and on 2
workers (the cluster started once, outside the timing: its start-up cost is its own row), checks
that the JSON is byte-identical, and sets the measured time on workers beside the model

    time ≈ jobs × mean job time / workers   (mean job time measured in the serial run)

so that ``ratio = workers / serial`` (goal ≤ 0.65 on 2 cores) and ``model_error`` are what to read;
``schedule_s`` adds the imbalance of unequal jobs (list scheduling of the measured job times) and
``load_avg`` says how busy the machine was (the model assumes the workers' cores are free).
"""

from __future__ import annotations

import heapq
import json
import math
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.evaluate.paper.compare import numbers, rows
from lfdfuse.evaluate.paper.suite import PaperOptions, Plan, plan_cells, run_experiments
from lfdfuse.execute.starts import StartsOptions, run_starts
from lfdfuse.network.table import write_table
from lfdfuse.parallel import Executor, Outcome, open_executor
from lfdfuse.parallel.jobs import check_after, critical_path_order
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented

SAMPLE = Path(__file__).resolve().parents[2] / "sample_logs" / "three-goals-building.mcap"
WORKERS = 2
GOAL_RATIO = 0.65

T = TypeVar("T")
R = TypeVar("R")


def _table(folder: Path) -> Path:
    seg = segment_file(SAMPLE, out=folder / "three-goals.seg.mcap", measure_lag=False)
    table, _, _ = estimate_run(read_segmented(seg.out), opts=EstimateOptions(seed=1), name="three-goals")
    path = folder / "three-goals.yaml"
    write_table(table, path)
    return path


def list_schedule_s(
    job_s: Sequence[float], workers: int, after: Sequence[Sequence[int]] | None = None
) -> float:
    """The makespan of jobs handed, in order, to whichever of ``workers`` is free first, each
    free worker taking the first job whose prerequisites (``after``: earlier jobs) are done — what
    Dask does with jobs in priority order: the model's ``jobs × mean / workers`` plus the
    imbalance of unequal jobs and the waits."""
    needs = check_after(after, len(job_s))
    end: dict[int, float] = {}
    free = [0.0] * workers
    todo = list(range(len(job_s)))
    while todo:
        now = heapq.heappop(free)
        job = next((i for i in todo if all(end.get(j, math.inf) <= now for j in needs[i])), None)
        if job is None:  # nothing can start yet: free again when the next running job ends
            heapq.heappush(free, min(t for t in end.values() if t > now))
            continue
        todo.remove(job)
        end[job] = now + job_s[job]
        heapq.heappush(free, end[job])
    return max(end.values(), default=0.0)


def chain_s(job_s: Sequence[float], after: Sequence[Sequence[int]]) -> float:
    """The costliest chain of jobs that wait for each other (no schedule is shorter)."""
    needs = check_after(after, len(job_s))
    ends: list[float] = []
    for i, t in enumerate(job_s):
        ends.append(t + max((ends[j] for j in needs[i]), default=0.0))
    return max(ends, default=0.0)


class _Timed:
    """An executor that keeps each job's wall time (the outcome's, by the job: a frozen cell)."""

    def __init__(self, inner: Executor) -> None:
        self.inner = inner
        self.seconds: dict[object, float] = {}

    @property
    def slots(self) -> int:
        return self.inner.slots

    def run(
        self, fn: Callable[[T], R], items: Sequence[T], *, after: Sequence[Sequence[int]] | None = None
    ) -> Iterator[Outcome[R]]:
        for out in self.inner.run(fn, items, after=after):
            self.seconds[items[out.index]] = out.seconds
            yield out


def _paper(folder: Path, executor: Executor, *, quick: bool) -> tuple[float, str, list[float], Plan]:
    """The report's grid (``make paper``; ``--quick`` in quick mode): wall time, report numbers as
    JSON, each cell's wall time (in the plan's order) and the plan."""
    opts = PaperOptions(logs=folder / "logs", seed=1, quick=quick)
    timed = _Timed(executor)
    t0 = time.perf_counter()
    events = list(run_experiments(opts, executor=timed))
    wall = time.perf_counter() - t0
    results = events[-1].results
    assert results is not None
    plan = plan_cells(opts)
    job_s = [timed.seconds[c] for c in plan.cells]
    return wall, json.dumps(numbers(results, tuple(rows(results)))), job_s, plan


def _paper_model(job_s: list[float], plan: Plan) -> dict[str, float]:
    """The grid's cost model from measured job times: total / workers, the critical-path bound,
    the list schedule in the batch's order (:func:`~lfdfuse.parallel.jobs.critical_path_order` of
    the plan's estimated costs, as :class:`~lfdfuse.parallel.Batch` hands them out)."""
    order = critical_path_order(plan.costs, plan.after)
    at = {job: k for k, job in enumerate(order)}
    after = [sorted(at[j] for j in plan.after[job]) for job in order]
    total = sum(job_s)
    model = total / WORKERS
    return {
        "total_job_s": round(total, 2),
        "longest_job_s": round(max(job_s), 2),
        "chain_s": round(chain_s(job_s, plan.after), 2),
        "model_s": round(model, 2),
        "bound_s": round(max(model, chain_s(job_s, plan.after)), 2),
        "schedule_s": round(list_schedule_s([job_s[j] for j in order], WORKERS, after), 2),
    }


def run(quick: bool = False) -> list[dict[str, Any]]:
    """Rows ``{name, jobs, serial_s, workers_s, ratio, model_s, model_error, identical}`` per grid size."""
    sizes = (2, 4, 6) if quick else (2, 4, 8)
    max_time = 40.0 if quick else 300.0
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        table = _table(Path(tmp))
        t0 = time.perf_counter()
        with open_executor(workers=WORKERS) as cluster:
            # start-up and each worker's first imports (numpy, shapely, scipy, lfdfuse) are paid once
            # per cluster, not per grid: measured here, outside the grid's timing
            warm = StartsOptions(table=table, world="building", starts=2 * WORKERS, max_time_s=1.0, seed=0)
            run_starts(warm, executor=cluster).result()
            rows.append(
                {
                    "name": "LocalCluster start + warm-up",
                    "workers": WORKERS,
                    "seconds": round(time.perf_counter() - t0, 2),
                }
            )
            with open_executor() as serial:
                # the paper's grid first (``make paper``): unequal cells, some waiting for others
                a_s, a_json, job_s, plan = _paper(Path(tmp) / "serial", serial, quick=quick)
                b_s, b_json, _, _ = _paper(Path(tmp) / "workers", cluster, quick=quick)
                paper = _paper_model(job_s, plan)
                rows.append(
                    {
                        "name": "paper grid" + (" (quick)" if quick else ""),
                        "jobs": len(job_s),
                        "serial_s": round(a_s, 2),
                        "workers_s": round(b_s, 2),
                        "ratio": round(b_s / a_s, 3),
                        "goal_ratio": GOAL_RATIO,
                        **paper,
                        "model_ratio": round(paper["schedule_s"] / a_s, 3),
                        "model_error": round(b_s / paper["schedule_s"] - 1.0, 3),
                        "identical": a_json == b_json,
                        "load_avg": round(os.getloadavg()[0], 1),
                    }
                )
                for n in sizes:
                    opts = StartsOptions(table=table, world="building", starts=n, max_time_s=max_time, seed=1)
                    t0 = time.perf_counter()
                    batch = run_starts(opts, executor=serial)
                    a = batch.result()
                    serial_s = time.perf_counter() - t0
                    job_s = [o.seconds for o in batch.outcomes]
                    mean_job = sum(job_s) / n
                    t0 = time.perf_counter()
                    b = run_starts(opts, executor=cluster).result()
                    workers_s = time.perf_counter() - t0
                    model = n * mean_job / WORKERS if n >= WORKERS else mean_job
                    rows.append(
                        {
                            "name": f"execute --starts {n}",
                            "jobs": n,
                            "mean_job_s": round(mean_job, 2),
                            "serial_s": round(serial_s, 2),
                            "workers_s": round(workers_s, 2),
                            "ratio": round(workers_s / serial_s, 3),
                            "goal_ratio": GOAL_RATIO if n >= WORKERS else None,
                            "model_s": round(model, 2),
                            "model_error": round(workers_s / model - 1.0, 3) if model > 0 else math.nan,
                            "schedule_s": round(list_schedule_s(job_s, WORKERS), 2),
                            # other processes on the machine take cores the model assumes free
                            "load_avg": round(os.getloadavg()[0], 1),
                            "identical": json.dumps(a.to_dict()) == json.dumps(b.to_dict()),
                        }
                    )
    return rows


if __name__ == "__main__":
    for row in run(quick="--quick" in sys.argv):
        print(row)
