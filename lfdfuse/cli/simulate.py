"""``lfdfuse simulate``."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import typer

from lfdfuse.cli.app import WORLD_HELP, app
from lfdfuse.cli.common import (
    check_amount,
    check_duration,
    check_outputs,
    check_seed,
    existing,
    progress_bar,
    user_errors,
)
from lfdfuse.cli.render import print_run
from lfdfuse.execute.run import ExecuteOptions, drive_table
from lfdfuse.files import read_yaml
from lfdfuse.network.table import load_table
from lfdfuse.sim.robot import Pose
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import STYLES, Leg, load_task, parse_style
from lfdfuse.sources.teachers import TeacherParams
from lfdfuse.world.model import DEFAULT_WORLD, load_world


@app.command("simulate")
@user_errors
def simulate_cmd(
    world: str = typer.Option(DEFAULT_WORLD, "--world", "-w", help=WORLD_HELP),
    teacher: str = typer.Option(
        "keep-left",
        "--teacher",
        "-t",
        help=f"A built-in style ({', '.join(STYLES)}), a task YAML, or a fusion table YAML (a network teacher).",
    ),
    duration: float = typer.Option(300.0, "--duration", "-d", help="Maximum simulated time in seconds."),
    seed: int = typer.Option(0, "--seed", help="Seed of every random draw (teacher noise, sensor noise)."),
    start: str | None = typer.Option(
        None, "--start", help="Start pose X,Y,THETA (m, m, rad); default: the world's."
    ),
    noise: float = typer.Option(
        0.0, "--sensor-noise", help="Std (m) of Gaussian range noise on laser and sonar."
    ),
    heading_noise: float | None = typer.Option(
        None,
        "--heading-noise",
        help="Teacher heading noise std in degrees (default 5; correlated for style teachers).",
    ),
    out: Path = typer.Option(Path("demo.mcap"), "--out", "-o", help="Output MCAP file."),
) -> None:
    """Drive a scripted teacher in a world and record the demonstration as MCAP.

    A style alone tours the map; a task YAML chains targets with styles and ends when the last
    target is reached; a fusion table drives the robot as a network teacher (a known ground
    truth for round trips), with --heading-noise added to its heading.

    Examples:
      lfdfuse simulate --world corridor --teacher keep-right -o right.mcap
      lfdfuse simulate --world building --teacher task.yaml --seed 3 -o task.mcap
      lfdfuse simulate --world building --teacher fusion.yaml --heading-noise 5 -o truth.mcap
    """
    check_duration("--duration", duration)
    check_seed(seed)
    check_amount("--sensor-noise", noise, maximum=1.0, unit="m")
    if heading_noise is not None:
        check_amount("--heading-noise", heading_noise, maximum=180.0, unit="degrees")
    check_outputs([out], [existing(world), existing(teacher)])
    w = load_world(world)
    pose = Pose.parse(start) if start is not None else None
    if teacher.endswith((".yaml", ".yml")) or existing(teacher):
        if is_fusion_table(Path(teacher)):
            tab = load_table(Path(teacher))
            eopts = ExecuteOptions(
                world=w,
                table=tab,
                table_name=Path(teacher).name,
                start=pose,
                max_time_s=duration,
                seed=seed,
                heading_noise_rad=math.radians(heading_noise if heading_noise is not None else 5.0),
                sensor_noise_m=noise,
            )
            with progress_bar("simulate") as update:
                res = drive_table(eopts, out=out, command="simulate", teacher=True, progress=update)
            print_run(res.summary, title=f"simulate {w.name} / network teacher {Path(teacher).name}")
            return
        legs, name = load_task(teacher), Path(teacher).name
    else:
        legs, name = [Leg(None, parse_style(teacher))], teacher
    tp = (
        TeacherParams()
        if heading_noise is None
        else replace(TeacherParams(), heading_noise_rad=math.radians(heading_noise))
    )
    opts = SimulateOptions(
        world=w,
        legs=legs,
        teacher_name=name,
        duration_s=duration,
        seed=seed,
        start=pose,
        sensor_noise_m=noise,
        teacher=tp,
    )
    with progress_bar("simulate") as update:
        summary = simulate(opts, out=out, progress=update)
    print_run(summary, title=f"simulate {w.name} / {name}")


def is_fusion_table(path: Path) -> bool:
    """A YAML whose top level has ``format:`` is a fusion table (a network teacher)."""
    data = read_yaml(path, what="teacher file")
    return isinstance(data, dict) and "format" in data
