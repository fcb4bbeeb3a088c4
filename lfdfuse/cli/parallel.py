"""What the commands that run many jobs share: ``--workers``/``--scheduler`` and a progress bar."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import typer
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from lfdfuse.cli.common import err_console
from lfdfuse.parallel import MAX_WORKERS, Event


def workers_option() -> Any:
    return typer.Option(
        None,
        "--workers",
        min=1,
        max=MAX_WORKERS,
        help="Run the jobs on a Dask LocalCluster of this many worker processes (default: in this process).",
    )


def scheduler_option() -> Any:
    return typer.Option(
        None,
        "--scheduler",
        help="Run the jobs on an existing Dask cluster, e.g. tcp://HOST:8786 (its workers need lfdfuse).",
    )


def one_executor(workers: int | None, scheduler: str | None) -> None:
    """Both options at once is a usage error (exit 2)."""
    if workers is not None and scheduler is not None:
        raise typer.BadParameter("give --workers or --scheduler, not both", param_hint="--workers")


def follow(label: str, events: Iterable[Event]) -> int:
    """Draw a batch's progress on stderr (done / running / failed, ETA) and print each failed job's
    own ``error:`` line as it comes; returns how many failed."""
    failed = 0
    with Progress(
        TextColumn(label),
        BarColumn(),
        TextColumn("{task.completed:.0f}/{task.total:.0f}"),
        TextColumn("{task.description}"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=err_console,
        transient=True,
        disable=not err_console.is_terminal,
    ) as bar:
        task = bar.add_task("", total=1)
        for ev in events:
            failed = ev.failed
            if ev.error is not None:
                line = ev.error if ev.label in ev.error else f"{ev.label}: {ev.error}"
                bar.console.print(f"error: {line}", markup=False, soft_wrap=True)
            bar.update(
                task,
                total=max(ev.total, 1),
                completed=ev.finished,
                description=f"running {ev.running}, failed {ev.failed}",
            )
    return failed
