"""``lfdfuse execute``."""

from __future__ import annotations

from pathlib import Path

import typer

from lfdfuse.cli.app import WORLD_HELP, app
from lfdfuse.cli.common import (
    check_outputs,
    checked,
    duration_option,
    err_console,
    existing,
    progress_bar,
    seed_option,
    sensor_noise_option,
    start_option,
    user_errors,
)
from lfdfuse.cli.execute_starts import execute_starts, starts_of
from lfdfuse.cli.parallel import one_executor, scheduler_option, workers_option
from lfdfuse.cli.render import print_report
from lfdfuse.execute.report import write_report
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.execute.starts import StartsOptions
from lfdfuse.network.stepper import check_table_world
from lfdfuse.network.table import load_table
from lfdfuse.robot.pose import Pose
from lfdfuse.world.model import DEFAULT_WORLD, load_world


@app.command("execute")
@user_errors
def execute_cmd(
    table: Path = typer.Argument(
        ..., help="A fusion table YAML (from `lfdfuse estimate`, or written by hand)."
    ),
    world: str = typer.Option(DEFAULT_WORLD, "--world", "-w", help=WORLD_HELP),
    start: str | None = start_option(),
    max_time: float = duration_option(300.0, "--max-time", help="Stop after this many simulated seconds."),
    seed: int = seed_option("Seed of every random draw (sensor noise)."),
    noise: float = sensor_noise_option(),
    stop_on_collision: bool = typer.Option(
        False, "--stop-on-collision", help="End the run at the first collision."
    ),
    out: Path | None = typer.Option(
        None,
        "--out",
        "-o",
        help="Run log (MCAP) with the /lfd/* channels and an overlay (default: run.mcap; not with --starts).",
    ),
    report: Path | None = typer.Option(None, "--report", help="Write the JSON report here."),
    starts: str | None = typer.Option(
        None,
        "--starts",
        callback=checked(lambda text: starts_of(text)),
        help="N: run from N starts perturbed ±0.5 m, ±20° around --start (seeded), or a YAML file listing"
        " poses (X,Y,THETA each); prints completed/N with a 95 % interval (no run logs are kept).",
    ),
    workers: int | None = workers_option(),
    scheduler: str | None = scheduler_option(),
) -> None:
    """Let a learned behaviour network drive the robot, log the run and report how it went.

    The run stops when the last goal is achieved or at --max-time.

    Examples:
      lfdfuse execute fusion.yaml --world building -o run.mcap --report run.json
      lfdfuse execute left.yaml --world tee --start 1,9,0 --max-time 120
      lfdfuse execute task.yaml --starts 10 --workers 2 --report rate.json
    """
    if starts is not None and out is not None:
        raise typer.BadParameter("--starts keeps no run logs: drop -o, or run from one --start to get a log")
    out = out or Path("run.mcap")
    check_outputs([out, report], [table, existing(world)])
    if starts is not None:
        one_executor(workers, scheduler)
        pose0 = Pose.parse(start) if start is not None else None
        many = StartsOptions(
            table=table,
            world=world,
            starts=starts_of(starts),
            base=pose0,
            max_time_s=max_time,
            seed=seed,
            sensor_noise_m=noise,
            stop_on_collision=stop_on_collision,
        )
        execute_starts(many, workers=workers, scheduler=scheduler, report=report)
        return
    if workers is not None or scheduler is not None:
        raise typer.BadParameter("--workers and --scheduler run many starts: give --starts too")
    w = load_world(world)
    tab = load_table(table)
    check_table_world(tab, w)  # a target the network steers to must exist: that is an error, said first
    unreachable = [g for g in dict.fromkeys(tab.goals()) if g not in w.target_names]
    if unreachable:
        err_console.print(
            f"warning: world {w.name!r} has no target {', '.join(unreachable)}: the goal"
            f"{'s' if len(unreachable) > 1 else ''} cannot be reached and the run goes on to --max-time",
            markup=False,
            soft_wrap=True,
        )
    pose = Pose.parse(start) if start is not None else None
    opts = ExecuteOptions(
        world=w,
        table=tab,
        table_name=table.name,
        start=pose,
        max_time_s=max_time,
        seed=seed,
        sensor_noise_m=noise,
        stop_on_collision=stop_on_collision,
    )
    with progress_bar("execute") as update:
        res = run_table(opts, out=out, command="execute", progress=update)
    if report is not None:
        write_report(res.report, report)
    print_report(res.report, out=str(out))
