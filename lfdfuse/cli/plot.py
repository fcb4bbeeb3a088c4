"""``lfdfuse plot``."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path

import typer

from lfdfuse.cli.app import app
from lfdfuse.cli.common import console, user_errors


class Whiskers(StrEnum):
    """``--whiskers``: the spread a fusion table's weight bars show."""

    #: the posterior std of each weight
    STD = "std"
    #: the spread over ``estimate --trials K``
    TRIAL_STD = "trial_std"


@app.command("plot")
@user_errors
def plot_cmd(
    src: Path = typer.Argument(
        ..., help="A demo, segmented or run MCAP (drawn on its map), or a fusion table YAML (weight bars)."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="The figure: PATH.png or PATH.svg."),
    whiskers: Whiskers = typer.Option(
        Whiskers.STD,
        "--whiskers",
        help="Fusion tables: std (posterior std) or trial_std (spread over --trials K).",
    ),
    title: str | None = typer.Option(None, "--title", help="Title instead of the default one."),
) -> None:
    """Draw a log on its map or a fusion table as weight bars.

    A log shows the walls, obstacles and targets, the path coloured by goal segment (segmented
    demo) or network step (run), the start, goals reached, BAC changes as ticks across the path
    and collisions. A table shows, per step, one group of bars per BAC row: the weight of each
    behaviour in its fixed colour, std whiskers, the BAC and its sample count.

    Examples:
      lfdfuse plot demo.seg.mcap -o demo.png
      lfdfuse plot run.mcap -o run.svg
      lfdfuse plot trials.yaml -o weights.png --whiskers trial_std
    """
    from lfdfuse.viz.plot import plot_file  # matplotlib only when plotting: `lfdfuse --help` stays fast

    res = plot_file(src, out, title=title, spread=whiskers.value)
    console.print(f"[bold]plot[/bold] {src} → {res.out}  ({res.width_px}×{res.height_px} px)")
    console.print(f"  {res.summary}")
