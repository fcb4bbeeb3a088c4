"""``lfdfuse execute TABLE --starts N|FILE``: the success rate over many starts, rendered."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import typer
from rich.table import Table

from lfdfuse.cli.common import console
from lfdfuse.cli.parallel import follow
from lfdfuse.cli.tables import show
from lfdfuse.errors import ConfigError
from lfdfuse.execute.starts import MAX_STARTS, StartsOptions, StartsResult, run_starts
from lfdfuse.files import write_text_atomic
from lfdfuse.parallel import open_executor
from lfdfuse.words import counted


def starts_of(text: str) -> int | Path:
    """``--starts 10`` (perturbed starts) or ``--starts poses.yaml`` (a file of poses)."""
    if not text.strip().lstrip("+-").isdigit():
        return Path(text)
    n = int(text)
    if not 1 <= n <= MAX_STARTS:
        raise ConfigError(f"--starts must be from 1 to {MAX_STARTS} starts, got {n}")
    return n


def _styles(run: dict[str, Any]) -> str:
    return ", ".join(f"{s['name']}:{s['style']}" for s in run["steps"]) or "-"


def execute_starts(
    opts: StartsOptions, *, workers: int | None, scheduler: str | None, report: Path | None
) -> None:
    with open_executor(workers=workers, scheduler=scheduler) as ex:
        batch = run_starts(opts, executor=ex)
        failed = follow("execute", batch)
        res = batch.result()
    if report is not None:
        write_text_atomic(report, json.dumps(res.to_dict(), indent=1) + "\n")
    print_starts(res, table=opts.table.name)
    if failed:
        raise typer.Exit(1)


def print_starts(res: StartsResult, *, table: str) -> None:
    rows = Table(box=None, header_style="bold")
    for col in ("#", "start x, y, θ", "completed", "goals", "collisions", "time s", "style per step"):
        rows.add_column(col, justify="left" if col in ("start x, y, θ", "style per step") else "right")
    for k, r in enumerate(res.runs, 1):
        x, y, th = r["start"]
        where = f"{x:.2f}, {y:.2f}, {th:+.2f}"
        if "error" in r:
            rows.add_row(str(k), where, "failed", "", "", "", str(r["error"]))
            continue
        done = "-" if r["completed"] is None else ("yes" if r["completed"] else "no")
        goals = f"{sum(g['reached'] for g in r['goals'])}/{len(r['goals'])}" if r["goals"] else "-"
        rows.add_row(str(k), where, done, goals, str(r["collisions"]), f"{r['duration_s']:.1f}", _styles(r))
    show(rows)
    fail = f" ({res.failed} failed to run)" if res.failed else ""
    if res.completed is None or res.ci95 is None or res.rate is None:
        head = f"[bold]execute[/bold] {table}: {res.ran} runs{fail}; the network has no goals, nothing to complete"
    else:
        lo, hi = res.ci95
        head = (
            f"[bold]execute[/bold] {table}: completed {res.completed}/{res.ran}{fail}"
            f" = {100 * res.rate:.0f} % (95 % interval {100 * lo:.0f}–{100 * hi:.0f} %)"
        )
    ok = [r for r in res.runs if "error" not in r]
    hits = sum(r["collisions"] > 0 for r in ok)
    console.print(
        f"{head}; {hits} of {len(ok)} runs collided ({counted(sum(r['collisions'] for r in ok), 'collision')})"
    )
