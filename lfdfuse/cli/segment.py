"""``lfdfuse segment``."""

from __future__ import annotations

from pathlib import Path

import typer

from lfdfuse.behaviors.primitives import DEFAULT_PRESET, PRESETS
from lfdfuse.cli.app import app, default_out
from lfdfuse.cli.common import check_outputs, checked, console, progress_bar, user_errors
from lfdfuse.cli.render import print_segments
from lfdfuse.errors import ConfigError
from lfdfuse.segment.commands import CommandChoice
from lfdfuse.segment.lag import CANDIDATE_LAGS_S
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
    lag: str = typer.Option(
        "auto",
        "--lag",
        callback=checked(lambda text: parse_lag(text)),
        help="Pair each scan with the command issued this many seconds later (reaction lag); auto: the best-explaining lag.",
    ),
    commands: CommandChoice = typer.Option(
        CommandChoice.AUTO,
        "--commands",
        help="How the teacher commands: continuous (on the drive mapping), discrete (a few keys, held), or auto (from the log).",
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
      lfdfuse segment demo.mcap --lag 0.3
      lfdfuse segment keyboard.mcap --commands discrete
    """
    lag_s = parse_lag(lag)
    if out is None and src.name.endswith(".seg.mcap"):
        raise ConfigError(f"{src} is segmented already: give -o to segment it again under another name")
    target = out or default_out(src, ".seg")
    check_outputs([target], [src])
    with progress_bar("segment") as progress:
        res = segment_file(
            src, out=target, behaviors=behaviors, lag_s=lag_s, commands=commands.mode, progress=progress
        )
    console.print(f"[bold]segment[/bold] {src} → {res.out}")
    console.print(f"  behaviours: {', '.join(res.names)}")
    still = int((~res.informative).sum())
    console.print(
        f"  {len(res.t_ns)} steps, {still} without heading information (standing still or reversing)"
    )
    best, here = res.best_lag, res.fit_at_lag
    if best is not None:
        now = f", {here.heading_error_deg:.1f}° at --lag {res.lag_s:g}" if here is not None else ""
        console.print(
            f"  command lag: {best.lag_s:+.1f} s explains the demo best "
            f"(per-BAC least-squares heading error {best.heading_error_deg:.1f}°{now})"
        )
    print_segments(res.segmentation, res.names, res.t_ns.tolist())


def parse_lag(text: str) -> float | None:
    """``--lag``: ``auto`` (None) or seconds."""
    if text.strip().lower() == "auto":
        return None
    try:
        lag_s = float(text)
    except ValueError:
        raise ConfigError(f"--lag must be a number of seconds or auto, got {text[:40]!r}") from None
    lo, hi = min(CANDIDATE_LAGS_S), max(CANDIDATE_LAGS_S)
    if not lo <= lag_s <= hi:
        raise ConfigError(f"--lag {text[:40]} is outside the {lo:g}–{hi:g} s the lag search covers")
    return lag_s
