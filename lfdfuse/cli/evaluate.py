"""``lfdfuse evaluate``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer
from rich.table import Table

from lfdfuse.cli.app import app
from lfdfuse.cli.common import check_outputs, console, seed_option, user_errors
from lfdfuse.cli.evaluate_corpus import print_corpus
from lfdfuse.cli.evaluate_many import print_logs
from lfdfuse.cli.parallel import follow, one_executor, scheduler_option, workers_option
from lfdfuse.cli.tables import show
from lfdfuse.estimate.methods import POINT_FITS, REGISTRY
from lfdfuse.evaluate.batch import evaluate_logs
from lfdfuse.evaluate.cloning import SECTORS
from lfdfuse.evaluate.corpus import expand_logs
from lfdfuse.evaluate.folds import FOLDS, MIN_DECISIONS, reading_folds
from lfdfuse.evaluate.holdout import Evaluation, MethodScore, reading
from lfdfuse.files import write_text_atomic
from lfdfuse.parallel import open_executor

_WHAT = {
    "fused": "the default estimator, fitted on the first part",
    **{m.value: f"{REGISTRY[m].label}, first part" for m in POINT_FITS},
    "straight": "always straight ahead",
    "previous": "the teacher's previous heading",
    "oracle": "the default estimator fitted on the held-out steps",
}
#: k-fold's methods: each fitted on the other folds (the oracle on its own)
_WHAT_FOLDS = {
    "fused": "the default estimator, fitted on the other folds",
    "nnls": "non-negative least squares, other folds",
    "arbitration": "best single behaviour per BAC, other folds",
    "bc": f"behaviour cloning: k-nearest neighbours from {SECTORS} scan sectors' nearest returns, other folds",
    "straight": "always straight ahead",
    "previous": "the teacher's previous heading",
    "oracle": "the default estimator fitted on the fold itself",
}


def fraction(value: float | None) -> float | None:
    """``--holdout``: a fraction strictly between 0 and 1 (a usage error otherwise)."""
    if value is not None and not (math.isfinite(value) and 0.0 < value < 1.0):
        raise typer.BadParameter(f"{value} is not a fraction between 0 and 1")
    return value


@app.command("evaluate")
@user_errors
def evaluate_cmd(
    srcs: list[Path] = typer.Argument(
        ...,
        metavar="LOG|DIR",
        help="Segmented demos (from `lfdfuse segment`); an lfdfuse demo is segmented and a robot log"
        " (bag, CARMEN, BreezySLAM) imported on the way. A folder: every robot log `import` reads"
        " under it (a rosbag2 folder is one log, whatever its name).",
    ),
    holdout: float | None = typer.Option(
        None,
        "--holdout",
        callback=fraction,
        help="Hold out the last part of each log by time, this fraction (between 0 and 1),"
        " instead of k-fold.",
    ),
    folds: int | None = typer.Option(
        None,
        "--folds",
        min=2,
        max=20,
        help=f"Blocked folds over the informative decisions, each scored by fits on the others"
        f" (default {FOLDS}; a log needs {MIN_DECISIONS}).",
    ),
    seed: int = seed_option("Seed of the estimator and the bootstrap."),
    json_out: Path | None = typer.Option(None, "--json", help="Write the scores as JSON here."),
    workers: int | None = workers_option(),
    scheduler: str | None = scheduler_option(),
) -> None:
    """Fit on part of a demo, predict the demonstrated heading on the rest.

    By default the demo's informative decisions are cut into 5 contiguous folds and every fold is
    predicted by tables fitted on the others (--holdout: the last part by time instead). Mean
    absolute heading error on the informative held-out steps, with a 95 % bootstrap interval and
    the spread over the folds, for the learned fusion beside baselines (behaviour cloning among
    them) and an oracle.

    Examples:
      lfdfuse evaluate demo.seg.mcap
      lfdfuse evaluate real.seg.mcap --holdout 0.3 --json eval.json
      lfdfuse evaluate ../shared/realdata/human --workers 2 --json all.json

    Given several logs or a folder: one row per log and a summary across logs (how often fused
    beats each baseline, the median difference and its bootstrap interval over the logs); a log
    that cannot be evaluated prints its own error line and its row says why, the rest carry on,
    and the exit code is 1.
    """
    one_executor(workers, scheduler)
    if holdout is not None and folds is not None:
        raise typer.BadParameter("give --holdout or --folds, not both", param_hint="--folds")
    paths, walked = expand_logs(srcs)
    check_outputs([json_out], list(paths))
    with open_executor(workers=workers, scheduler=scheduler) as ex:
        batch = evaluate_logs(paths, holdout=holdout, seed=seed, folds=folds or FOLDS, executor=ex)
        failed = follow("evaluate", batch)
        res = batch.result()
    if walked or len(paths) > 1:
        if json_out is not None:
            write_text_atomic(json_out, json.dumps(res.to_dict(), indent=1) + "\n")
        if holdout is None:
            print_corpus(res)
        else:
            print_logs(res)
        if failed:
            raise typer.Exit(1)
        return
    if failed:
        raise typer.Exit(1)
    src, ev = paths[0], res.evaluations[0].evaluation
    if json_out is not None:
        write_text_atomic(json_out, json.dumps(ev.to_dict(), indent=1) + "\n")
    lag = "unknown" if ev.lag_s is None else f"{ev.lag_s:g} s"
    kfold = ev.split == "kfold"
    if kfold:
        console.print(
            f"[bold]evaluate[/bold] {src}: {ev.folds} blocked folds over {ev.informative_decisions} informative"
            f" decisions, each predicted by fits on the others (about {ev.train_steps} steps each);"
            f" scored on {ev.test_steps} steps, command lag {lag}"
        )
    else:
        console.print(
            f"[bold]evaluate[/bold] {src}: trained on {ev.train_steps} steps, scored on {ev.test_steps} held-out steps"
            f" (last {100 * (holdout or 0.0):.0f} %), command lag {lag}"
        )
    table = Table(box=None, header_style="bold")
    table.add_column("method")
    table.add_column("error °", justify="right")
    if kfold:
        table.add_column("± folds", justify="right")
    table.add_column("95 % interval", justify="right")
    table.add_column("median °", justify="right")
    table.add_column(f"turns ° ({ev.turning_steps})", justify="right")
    if ev.test_decisions is not None:
        table.add_column(f"commands ({ev.test_decisions} decisions)", justify="right")
    for name, s in ev.methods.items():
        table.add_row(name, *_cells(ev, s))
    show(table)
    what = _WHAT_FOLDS if kfold else _WHAT
    console.print("  " + "; ".join(f"{k}: {v}" for k, v in what.items() if k in ev.methods) + ".")
    for line in [*reading(ev), *(reading_folds(ev) if kfold else [])]:
        console.print(f"  {line}")


def _cells(ev: Evaluation, s: MethodScore) -> list[str]:
    """One method's row of the single-log table (the ± folds column only for k-fold)."""
    spread = [] if s.fold_sd_deg is None else [f"{s.fold_sd_deg:.1f}"]
    acc = [] if s.command_accuracy is None else [f"{100 * s.command_accuracy:.0f} %"]
    return [
        f"{s.heading_error_deg:.1f}",
        *spread,
        f"{s.ci95_deg[0]:.1f}–{s.ci95_deg[1]:.1f}",
        f"{s.median_deg:.1f}",
        f"{s.turning_error_deg:.1f}" if ev.turning_steps else "—",  # no turn held out: no score
        *acc,
    ]
