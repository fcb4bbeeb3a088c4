"""``lfdfuse report``."""

from __future__ import annotations

import time
from pathlib import Path

import typer

from lfdfuse.cli.app import app
from lfdfuse.cli.common import console, err_console, seed_option, user_errors
from lfdfuse.cli.parallel import one_executor, scheduler_option, workers_option
from lfdfuse.parallel import open_executor


@app.command("report")
@user_errors
def report_cmd(
    out: Path = typer.Option(Path("paper-report"), "--out", "-o", help="Folder of the report (created)."),
    seed: int = seed_option("Seed of every demonstration, estimate and run.", default=1),
    quick: bool = typer.Option(
        False,
        "--quick",
        help="Shorter runs, fewer starts, 2 estimation trials: a smoke test of the report (~30 s).",
    ),
    scale: int = typer.Option(
        1,
        "--scale",
        min=1,
        max=100,
        help="A larger grid: the three-goal task from 6 x SCALE starts and 3 x SCALE obstacle runs per"
        " controller (rates with tighter 95 % intervals).",
    ),
    workers: int | None = workers_option(),
    scheduler: str | None = scheduler_option(),
) -> None:
    """Rerun the paper's experiments and write DIR/index.html, the figures and DIR/report.json.

    Styles demonstrated in the small world (tee) and run in the small and the large one
    (building) with the range-to-wall measure and the T-junction choice (paper Figs. 6, 7, 9-11; Fig. 5, scenario 1, is not rerun); the
    three-goal task from several starts (Section V-B.1); the weights over 30 estimation trials
    (Figs. 12-14); obstacle passing (Fig. 15). The table beside each figure sets the paper's
    result next to ours, measured in this run. `make paper` runs it into build/paper.

    Examples:
      lfdfuse report -o build/paper
      lfdfuse report -o /tmp/smoke --quick
      lfdfuse report -o build/paper-x4 --scale 4 --workers 2
    """
    one_executor(workers, scheduler)
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    from lfdfuse.evaluate.paper.compare import rows
    from lfdfuse.evaluate.paper.suite import PaperOptions, run_experiments
    from lfdfuse.viz.html import markdown_table  # matplotlib only when reporting
    from lfdfuse.viz.report import write_report

    began = time.monotonic()
    results = None
    with Progress(
        TextColumn("report"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TextColumn("{task.description}"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=err_console,
        transient=True,
        disable=not err_console.is_terminal,
    ) as bar:
        task = bar.add_task("", total=1)
        opts = PaperOptions(logs=out / "logs", seed=seed, quick=quick, scale=scale)
        with open_executor(workers=workers, scheduler=scheduler) as executor:
            for ev in run_experiments(opts, executor=executor):
                last = f"; last: {ev.label}" if ev.done else f"; {ev.label}"
                bar.update(
                    task,
                    total=ev.total + 1,
                    completed=ev.done,
                    description=f"running {ev.running}{last}",
                )
                results = ev.results or results
        assert results is not None
        bar.update(task, description="figures")
        result = write_report(results, tuple(rows(results)), out=out)
    agree = sum(r.agrees is True for r in result.comparison)
    differ = sum(r.agrees is False for r in result.comparison)
    console.print(
        f"[bold]report[/bold] → {out / 'index.html'}  ({len(result.figures)} figures, "
        f"{time.monotonic() - began:.0f} s)"
    )
    if quick:
        console.print(
            f"  {len(result.comparison)} results measured; a --quick smoke run judges none against the paper"
            " (too few runs per controller): run without --quick for the verdicts"
        )
    else:
        console.print(
            f"  {agree} results agree with the paper, {differ} differ, "
            f"{len(result.comparison) - agree - differ} not comparable"
        )
    console.print(markdown_table(result.comparison), markup=False, soft_wrap=True)
