"""``lfdfuse estimate``."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import typer

from lfdfuse.cli.app import app
from lfdfuse.cli.common import check_outputs, console, progress_bar, seed_option, user_errors
from lfdfuse.cli.render import print_table
from lfdfuse.estimate.methods import EstimateOptions, Likelihood, Method
from lfdfuse.estimate.paper import PFParams
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.learn import LearnOptions, learn
from lfdfuse.network.table import write_table


@app.command("estimate")
@user_errors
def estimate_cmd(
    src: Path = typer.Argument(..., help="A segmented log (from `lfdfuse segment`)."),
    method: Method = typer.Option(
        Method.PF,
        "--method",
        "-m",
        help="pf (exact posterior: Dirichlet prior, von Mises heading noise, tempered SMC), paper (the "
        "paper's particle filter as published), nnls (least squares) or arbitration (best single behaviour).",
    ),
    particles: int = typer.Option(
        SMCParams().particles,
        "--particles",
        min=1,
        max=100_000,
        help="Particles per row and trial (pf, paper).",
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
        help="Turn-offs the teacher took into an opening (a spur, a room) become landmark sub-goal steps.",
    ),
    out: Path = typer.Option(Path("fusion.yaml"), "--out", "-o", help="Output fusion table (YAML)."),
) -> None:
    """Estimate fusion weights per goal segment and BAC, and write the behaviour network.

    Rows marked * have fewer samples than can be trusted (low_samples in the YAML).

    Examples:
      lfdfuse estimate demo.seg.mcap
      lfdfuse estimate demo.seg.mcap --trials 30 -o fusion.yaml
      lfdfuse estimate demo.seg.mcap --method nnls -o nnls.yaml
    """
    check_outputs([out], [src])
    pf = replace(PFParams(), particles=particles, likelihood=likelihood.literal)
    smc = replace(SMCParams(), particles=particles)
    opts = EstimateOptions(method=method, trials=trials, seed=seed, pf=pf, smc=smc)
    with progress_bar("estimate") as update:
        res = learn([src], options=LearnOptions(estimate=opts, subgoals=subgoals), progress=update)
    write_table(res.table, out)
    console.print(
        f"[bold]estimate[/bold] {src} → {out}  ({method}, {trials} trial{'s' if trials > 1 else ''}, {res.groups} groups)"
    )
    print_table(res.table)
