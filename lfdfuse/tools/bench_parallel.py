"""Many runs at once (issue 22): serial against a 2-worker Dask ``LocalCluster``, same run, same grid.

First the paper's grid itself (``make paper``: every cell of the report, serial and on the
workers, the report's numbers byte-identical). Then the cost model on a grid of equal jobs,
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
from pathlib import Path
from typing import Any

from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.evaluate.paper.compare import numbers, rows
from lfdfuse.evaluate.paper.suite import PaperOptions, run_experiments
from lfdfuse.execute.starts import StartsOptions, run_starts
from lfdfuse.network.table import write_table
from lfdfuse.parallel import Executor, open_executor
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented

SAMPLE = Path(__file__).resolve().parents[2] / "sample_logs" / "three-goals-building.mcap"
WORKERS = 2
GOAL_RATIO = 0.65


def _table(folder: Path) -> Path:
    seg = segment_file(SAMPLE, out=folder / "three-goals.seg.mcap", measure_lag=False)
    table, _, _ = estimate_run(read_segmented(seg.out), opts=EstimateOptions(seed=1), name="three-goals")
    path = folder / "three-goals.yaml"
    write_table(table, path)
    return path


def list_schedule_s(job_s: list[float], workers: int) -> float:
    """The makespan of jobs handed, in order, to whichever of ``workers`` is free first (what Dask
    does with equal jobs): the model's ``jobs × mean / workers`` plus the imbalance of unequal jobs."""
    free = [0.0] * workers
    for t in job_s:
        heapq.heappush(free, heapq.heappop(free) + t)
    return max(free)


def _paper(folder: Path, executor: Executor, *, quick: bool) -> tuple[float, str, int]:
    """The report's grid (``make paper``; ``--quick`` in quick mode): wall time, report numbers as
    JSON, number of cells."""
    t0 = time.perf_counter()
    events = list(run_experiments(PaperOptions(logs=folder / "logs", seed=1, quick=quick), executor=executor))
    wall = time.perf_counter() - t0
    results = events[-1].results
    assert results is not None
    return wall, json.dumps(numbers(results, tuple(rows(results)))), events[-1].total


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
                # the paper's grid first (``make paper``): two waves of unequal cells
                a_s, a_json, cells = _paper(Path(tmp) / "serial", serial, quick=quick)
                b_s, b_json, _ = _paper(Path(tmp) / "workers", cluster, quick=quick)
                rows.append(
                    {
                        "name": "paper grid" + (" (quick)" if quick else ""),
                        "jobs": cells,
                        "serial_s": round(a_s, 2),
                        "workers_s": round(b_s, 2),
                        "ratio": round(b_s / a_s, 3),
                        "goal_ratio": GOAL_RATIO,
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
