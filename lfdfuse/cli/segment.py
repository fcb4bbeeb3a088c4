"""``lfdfuse segment``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from lfdfuse.behaviors.primitives import DEFAULT_PRESET, PRESETS
from lfdfuse.cli.app import app, default_out
from lfdfuse.cli.common import console, progress_bar, user_errors
from lfdfuse.cli.render import print_segments
from lfdfuse.segment.pipeline import segment_file


@app.command("segment")
@user_errors
def segment_cmd(
    src: Path = typer.Argument(..., help="A demonstration log (simulate, teleop or import)."),
    behaviors: str = typer.Option(
        DEFAULT_PRESET,
        "--behaviors",
        "-b",
        help=f"A preset ({', '.join(PRESETS)}) or a comma list of behaviour names.",
    ),
    out: Path | None = typer.Option(
        None, "--out", "-o", help="Output MCAP (default: IN with .seg before .mcap)."
    ),
) -> None:
    """Compute the behaviour primitives over a demo, split it at goals and BAC changes.

    Writes every input channel plus /lfd/behaviors, /lfd/demo, /lfd/bac and /lfd/segment.

    Examples:
      lfdfuse segment demo.mcap
      lfdfuse segment demo.mcap --behaviors full -o demo.full.seg.mcap
      lfdfuse segment demo.mcap --behaviors avoid,attract,wander_left,wander_right
    """
    target = out or default_out(src, ".seg")
    with progress_bar("segment"):
        res = segment_file(src, out=target, behaviors=behaviors)
    console.print(f"[bold]segment[/bold] {src} → {res.out}")
    console.print(f"  behaviours: {', '.join(res.names)}")
    dt = 0.1
    if len(res.t_ns) > 1:
        dt = float(np.median(np.diff(res.t_ns))) / 1e9
    still = int((~res.informative).sum())
    console.print(f"  {len(res.t_ns)} steps, {still} without heading information (standing still)")
    print_segments(res.segmentation, res.names, dt)
