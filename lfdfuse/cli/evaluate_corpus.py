"""``lfdfuse evaluate DIR…`` (k-fold): a row per log, and fused against each method across logs."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from rich.table import Table

from lfdfuse.cli.common import console
from lfdfuse.cli.tables import show
from lfdfuse.evaluate.batch import LogEvaluation, LogsResult
from lfdfuse.evaluate.folds import KFOLD_METHODS


def labels(paths: list[str]) -> list[str]:
    """File names when they tell the logs apart, else the paths below the folder they share."""
    short = [Path(p).name for p in paths]
    if len(set(short)) == len(short):
        return short
    if len(paths) < 2:
        return paths
    common = os.path.commonpath([os.path.abspath(p) for p in paths])
    return [os.path.relpath(os.path.abspath(p), common) for p in paths]


def _reason(path: str, error: str) -> str:
    """A failed log's error, without its own path (the row names it) and on one line."""
    text = error.removeprefix(f"{path}: ").replace("\n", " ")
    return f"not scored: {text}"


def print_corpus(res: LogsResult) -> None:
    """A row per log (mean held-out heading error per method, °; turning steps; commands), the
    reason a log was not scored in its row, then the comparison across logs."""
    methods = res.methods if res.evaluations else KFOLD_METHODS
    table = Table(box=None, header_style="bold")
    table.add_column("log", no_wrap=True, min_width=12)
    table.add_column("decisions", justify="right")
    table.add_column("steps", justify="right")
    for name in methods:
        table.add_column(name, justify="right")
    table.add_column("turns ° fused/straight", justify="right")
    table.add_column("keys fused/straight", justify="right")
    table.add_column("note")
    paths = [r.path if isinstance(r, LogEvaluation) else r[0] for r in res.rows]
    for row, label in zip(res.rows, labels(paths), strict=True):
        if isinstance(row, LogEvaluation):
            ev = row.evaluation
            m = ev.methods
            turns = "—"
            if ev.turning_steps:
                turns = f"{m['fused'].turning_error_deg:.1f}/{m['straight'].turning_error_deg:.1f}"
            keys = "—"
            f_acc, s_acc = m["fused"].command_accuracy, m["straight"].command_accuracy
            if f_acc is not None and s_acc is not None:
                keys = f"{100 * f_acc:.0f}/{100 * s_acc:.0f} %"
            table.add_row(
                label,
                str(ev.informative_decisions),
                str(ev.test_steps),
                *(f"{m[k].heading_error_deg:.1f}" for k in methods),
                turns,
                keys,
                "",
            )
        else:
            table.add_row(label, *([""] * (len(methods) + 4)), _reason(*row))
    summary = res.summary()
    n, failed = summary["logs"], summary["failed"]
    fail = f", {failed} not scored" if failed else ""
    console.print(
        f"[bold]evaluate[/bold] {n + failed} logs, each in blocked folds over its informative decisions:"
        f" mean absolute held-out heading error (°){fail}"
    )
    show(table)
    if n == 0:
        console.print("  no log could be evaluated")
        return
    means = summary["mean_heading_error_deg"]
    console.print(
        "  mean over logs: " + ", ".join(f"{m} {means[m]:.1f}°" for m in methods if means[m] is not None)
    )
    console.print(
        f"  fused against each method over the {n} scored logs (Δ = fused − method, per log; median over"
        " the logs and its 95 % bootstrap interval):"
    )
    show(_compare_table(summary["compare"]))


def _cmp_cells(c: dict[str, Any], *, percent: bool = False) -> list[str]:
    if not c["of"]:
        return ["—", "", ""]
    scale, unit = (100.0, " %") if percent else (1.0, "°")
    lo, hi = c["ci95"]
    return [
        f"{c['better'] + (c['ties'] if percent else 0)}/{c['of']}",
        f"{scale * c['median_diff']:+.1f}{unit}",
        f"{scale * lo:+.1f} to {scale * hi:+.1f}",
    ]


def _compare_table(compare: dict[str, Any]) -> Table:
    table = Table(box=None, header_style="bold")
    table.add_column("  method")
    for what in ("error: fused better", "median Δ", "95 % interval"):
        table.add_column(what, justify="right")
    for what in ("turns: fused better", "median Δ", "95 % interval"):
        table.add_column(what, justify="right")
    for what in ("keys: fused ≥", "median Δ", "95 % interval"):
        table.add_column(what, justify="right")
    for name, c in compare.items():
        table.add_row(
            f"  {name}" + (" (floor)" if name == "oracle" else ""),
            *_cmp_cells(c["heading_error_deg"]),
            *_cmp_cells(c["turning_error_deg"]),
            *_cmp_cells(c["command_accuracy"], percent=True),
        )
    return table
