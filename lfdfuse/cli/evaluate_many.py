"""``lfdfuse evaluate LOG LOG…``: one row per log and the summary across logs, rendered."""

from __future__ import annotations

from pathlib import Path

from rich.table import Table

from lfdfuse.cli.common import console
from lfdfuse.cli.tables import show
from lfdfuse.evaluate.batch import BASELINES, LogEvaluation, LogsResult
from lfdfuse.evaluate.holdout import METHODS


def print_logs(res: LogsResult) -> None:
    """A row per log (mean held-out heading error per method, °), then how often fused wins."""
    table = Table(box=None, header_style="bold")
    table.add_column("log", no_wrap=True, min_width=12)
    table.add_column("train", justify="right")
    table.add_column("test", justify="right")
    for name in METHODS:
        table.add_column(name, justify="right")
    names = [r.path if isinstance(r, LogEvaluation) else r[0] for r in res.rows]
    short = [Path(p).name for p in names]
    shown = short if len(set(short)) == len(short) else names  # file names when they tell the logs apart
    for row, label in zip(res.rows, shown, strict=True):
        if isinstance(row, LogEvaluation):
            ev = row.evaluation
            table.add_row(
                label,
                str(ev.train_steps),
                str(ev.test_steps),
                *(f"{ev.methods[m].heading_error_deg:.1f}" for m in METHODS),
            )
        else:
            table.add_row(label, "", "", "failed", *([""] * (len(METHODS) - 1)))
    summary = res.summary()
    n, failed = summary["logs"], summary["failed"]
    fail = f", {failed} could not be evaluated" if failed else ""
    console.print(f"[bold]evaluate[/bold] {n + failed} logs: mean absolute held-out heading error (°){fail}")
    show(table)
    if n == 0:
        console.print("  no log could be evaluated")
        return
    means = summary["mean_heading_error_deg"]
    console.print(
        "  mean over logs: " + ", ".join(f"{m} {means[m]:.1f}°" for m in METHODS if means[m] is not None)
    )
    for b in BASELINES:
        w = summary["fused_beats"][b]
        lo, hi = w["ci95"]
        console.print(
            f"  fused beats {b} on {w['logs']}/{w['of']} logs (95 % interval {100 * lo:.0f}–{100 * hi:.0f} %)"
        )
