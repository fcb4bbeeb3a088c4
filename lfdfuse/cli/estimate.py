"""``lfdfuse estimate``."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import typer

from lfdfuse.cli.app import app
from lfdfuse.cli.common import check_outputs, console, progress_bar, seed_option, user_errors
from lfdfuse.cli.render import print_changes, print_table
from lfdfuse.estimate.methods import REGISTRY, EstimateOptions, Likelihood, Method
from lfdfuse.estimate.paper import PFParams
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.learn import LearnOptions, learn
from lfdfuse.network.table import load_table, write_table
from lfdfuse.segment.commands import CommandChoice
from lfdfuse.words import counted


@app.command("estimate")
@user_errors
def estimate_cmd(
    srcs: list[Path] = typer.Argument(
        ...,
        help="Segmented logs (from `lfdfuse segment`): one demo, or several pooled into one table "
        "(goal steps matched by goal; a correction log from `teleop --table` adds its person's ticks).",
        metavar="DEMO...",
    ),
    method: Method = typer.Option(
        Method.PF,
        "--method",
        "-m",
        help=", ".join(f"{m.value} ({REGISTRY[m].label})" for m in Method) + ".",
    ),
    particles: int = typer.Option(
        SMCParams().particles,
        "--particles",
        min=1,
        max=100_000,
        help="Particles per row and trial (pf, paper); pf gives a keyboard demo of few decisions four"
        " times as many.",
    ),
    trials: int = typer.Option(
        1,
        "--trials",
        "-k",
        min=1,
        max=1000,
        help="Independent samplers (pf, paper; one vectorised pass) or bootstrap fits (nnls, arbitration); "
        "their spread is reported as trial_std.",
    ),
    likelihood: Likelihood = typer.Option(
        Likelihood.PAPER,
        "--likelihood",
        help="paper filter's likelihood: paper (2 - D/2, as published) or vonmises.",
    ),
    seed: int = seed_option("Seed of the filters' random draws."),
    subgoals: bool = typer.Option(
        False,
        "--subgoals",
        help="Turn-offs the teacher took into an opening (a spur, a room) become landmark sub-goal steps;"
        " with several demos, decisions are matched across them (a correction's turn into an opening the"
        " network passed by becomes one, inside the sub-step its network was in).",
    ),
    commands: CommandChoice = typer.Option(
        CommandChoice.AUTO,
        "--commands",
        help="Command model: continuous (on the drive mapping), discrete (a few keys, one observation per "
        "decision) or auto (what segment found in the log).",
    ),
    out: Path = typer.Option(Path("fusion.yaml"), "--out", "-o", help="Output fusion table (YAML)."),
) -> None:
    """Estimate fusion weights per goal segment and BAC, and write the behaviour network.

    Rows marked * have fewer samples than can be trusted (low_samples in the YAML).

    Examples:
      lfdfuse estimate demo.seg.mcap
      lfdfuse estimate demo.seg.mcap --trials 30 -o fusion.yaml
      lfdfuse estimate demo.seg.mcap --method nnls -o nnls.yaml
      lfdfuse estimate a.seg.mcap b.seg.mcap c.seg.mcap -o pooled.yaml
      lfdfuse estimate demo.seg.mcap correction.seg.mcap -o corrected.yaml
      lfdfuse estimate demo.seg.mcap fix.seg.mcap --subgoals -o fixed.yaml
    """
    check_outputs([out], list(srcs))
    pf = replace(PFParams(), particles=particles, likelihood=likelihood.literal)
    smc = replace(SMCParams(), particles=particles)
    opts = EstimateOptions(method=method, trials=trials, seed=seed, pf=pf, smc=smc, commands=commands.mode)
    with progress_bar("estimate") as update:
        res = learn(srcs, options=LearnOptions(estimate=opts, subgoals=subgoals), progress=update)
    write_table(res.table, out)
    what = str(srcs[0]) if len(srcs) == 1 else f"{len(srcs)} demos"
    rows = res.groups - res.skipped
    kept = f"{res.groups} groups" if not res.skipped else f"{res.groups} groups, {rows} rows"
    console.print(f"[bold]estimate[/bold] {what} → {out}  ({method}, {counted(trials, 'trial')}, {kept})")
    if res.skipped:
        console.print(
            f"  {counted(res.skipped, 'group')} had no informative step (standing still or reversing"
            " throughout): no row, the default weights drive there"
        )
    written = load_table(out)  # shown as written: the numbers inspect shows, rounded once
    print_table(written)
    print_changes(written)
    if res.repair is not None:
        for line in res.repair.describe():
            console.print(line, markup=False)
    if res.verdicts:
        console.print(f"decisions over {len(res.sources)} demos:")
        for v in res.verdicts:
            console.print(f"  {v.describe()}", markup=False, soft_wrap=True)
    if res.lesson is not None:
        console.print(res.lesson.describe(), markup=False, soft_wrap=True)
