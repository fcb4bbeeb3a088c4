"""``lfdfuse evaluate``."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.table import Table

from lfdfuse.cli.app import app
from lfdfuse.cli.common import check_outputs, console, seed_option, user_errors
from lfdfuse.cli.evaluate_many import print_logs
from lfdfuse.cli.parallel import follow, one_executor, scheduler_option, workers_option
from lfdfuse.estimate.methods import POINT_FITS, REGISTRY
from lfdfuse.evaluate.batch import evaluate_logs
from lfdfuse.evaluate.holdout import METHODS, reading
from lfdfuse.files import write_text_atomic
from lfdfuse.parallel import open_executor

_WHAT = {
    "fused": "the default estimator, fitted on the first part",
    **{m.value: f"{REGISTRY[m].label}, first part" for m in POINT_FITS},
    "straight": "always straight ahead",
    "previous": "the teacher's previous heading",
    "oracle": "the default estimator fitted on the held-out steps",
}


@app.command("evaluate")
@user_errors
def evaluate_cmd(
    srcs: list[Path] = typer.Argument(
        ...,
        metavar="LOG",
        help="Segmented demos (from `lfdfuse segment`); an lfdfuse demo is segmented and a robot log"
        " (bag, CARMEN, BreezySLAM) imported on the way.",
    ),
    holdout: float = typer.Option(
        0.3, "--holdout", help="Fraction of the log (its last part) held out, between 0 and 1."
    ),
    seed: int = seed_option("Seed of the estimator and the bootstrap."),
    json_out: Path | None = typer.Option(None, "--json", help="Write the scores as JSON here."),
    workers: int | None = workers_option(),
    scheduler: str | None = scheduler_option(),
) -> None:
    """Fit on the first part of a demo, predict the demonstrated heading on the rest.

    Mean absolute heading error on informative held-out steps, with a 95 % bootstrap interval,
    for the learned fusion beside baselines and an oracle.

    Examples:
      lfdfuse evaluate demo.seg.mcap
      lfdfuse evaluate real.seg.mcap --holdout 0.3 --json eval.json
      lfdfuse evaluate logs/*.seg.mcap --workers 2 --json all.json

    Given several logs: one row per log and a summary across logs (how often fused beats each
    baseline); a log that cannot be evaluated prints its own error line, the rest carry on, and
    the exit code is 1.
    """
    one_executor(workers, scheduler)
    check_outputs([json_out], list(srcs))
    with open_executor(workers=workers, scheduler=scheduler) as ex:
        batch = evaluate_logs(srcs, holdout=holdout, seed=seed, executor=ex)
        failed = follow("evaluate", batch)
        res = batch.result()
    if len(srcs) > 1:
        if json_out is not None:
            write_text_atomic(json_out, json.dumps(res.to_dict(), indent=1) + "\n")
        print_logs(res)
        if failed:
            raise typer.Exit(1)
        return
    if failed:
        raise typer.Exit(1)
    src, ev = srcs[0], res.evaluations[0].evaluation
    if json_out is not None:
        write_text_atomic(json_out, json.dumps(ev.to_dict(), indent=1) + "\n")
    lag = "unknown" if ev.lag_s is None else f"{ev.lag_s:g} s"
    console.print(
        f"[bold]evaluate[/bold] {src}: trained on {ev.train_steps} steps, scored on {ev.test_steps} held-out steps"
        f" (last {100 * holdout:.0f} %), command lag {lag}"
    )
    table = Table(box=None, header_style="bold")
    table.add_column("method")
    table.add_column("error °", justify="right")
    table.add_column("95 % interval", justify="right")
    table.add_column("median °", justify="right")
    table.add_column(f"turns ° ({ev.turning_steps})", justify="right")
    if ev.test_decisions is not None:
        table.add_column(f"commands ({ev.test_decisions} decisions)", justify="right")
    for name in METHODS:
        s = ev.methods[name]
        acc = [] if s.command_accuracy is None else [f"{100 * s.command_accuracy:.0f} %"]
        table.add_row(
            name,
            f"{s.heading_error_deg:.1f}",
            f"{s.ci95_deg[0]:.1f}–{s.ci95_deg[1]:.1f}",
            f"{s.median_deg:.1f}",
            f"{s.turning_error_deg:.1f}" if ev.turning_steps else "—",  # no turn held out: no score
            *acc,
        )
    console.print(table)
    console.print("  " + "; ".join(f"{k}: {v}" for k, v in _WHAT.items()) + ".")
    for line in reading(ev):
        console.print(f"  {line}")
