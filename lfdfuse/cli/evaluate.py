"""``lfdfuse evaluate``."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.table import Table

from lfdfuse.cli.app import app
from lfdfuse.cli.common import console, progress_bar, seed_option, user_errors
from lfdfuse.evaluate.holdout import METHODS, evaluate, reading
from lfdfuse.files import write_text_atomic
from lfdfuse.segment.read import read_segmented

_WHAT = {
    "fused": "the default estimator, fitted on the first part",
    "nnls": "non-negative least squares, first part",
    "arbitration": "best single behaviour per BAC, first part",
    "straight": "always straight ahead",
    "previous": "the teacher's previous heading",
    "oracle": "the default estimator fitted on the held-out steps",
}


@app.command("evaluate")
@user_errors
def evaluate_cmd(
    src: Path = typer.Argument(..., help="A segmented demo (from `lfdfuse segment`)."),
    holdout: float = typer.Option(
        0.3, "--holdout", help="Fraction of the log (its last part) held out, between 0 and 1."
    ),
    seed: int = seed_option("Seed of the estimator and the bootstrap."),
    json_out: Path | None = typer.Option(None, "--json", help="Write the scores as JSON here."),
) -> None:
    """Fit on the first part of a demo, predict the demonstrated heading on the rest.

    Mean absolute heading error on informative held-out steps, with a 95 % bootstrap interval,
    for the learned fusion beside baselines and an oracle.

    Examples:
      lfdfuse evaluate demo.seg.mcap
      lfdfuse evaluate real.seg.mcap --holdout 0.3 --json eval.json
    """
    run = read_segmented(src)
    with progress_bar("evaluate") as update:
        ev = evaluate(run, holdout=holdout, seed=seed, progress=update)
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
    for name in METHODS:
        s = ev.methods[name]
        table.add_row(
            name,
            f"{s.heading_error_deg:.1f}",
            f"{s.ci95_deg[0]:.1f}–{s.ci95_deg[1]:.1f}",
            f"{s.median_deg:.1f}",
            f"{s.turning_error_deg:.1f}",
        )
    console.print(table)
    console.print("  " + "; ".join(f"{k}: {v}" for k, v in _WHAT.items()) + ".")
    for line in reading(ev):
        console.print(f"  {line}")
