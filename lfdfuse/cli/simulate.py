"""``lfdfuse simulate``."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import typer

from lfdfuse.cli.app import WORLD_HELP, app
from lfdfuse.cli.common import (
    check_outputs,
    duration_option,
    existing,
    finite,
    progress_bar,
    seed_option,
    sensor_noise_option,
    start_option,
    user_errors,
)
from lfdfuse.cli.render import print_run
from lfdfuse.errors import ConfigError
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.network.table import parse_table
from lfdfuse.robot.pose import Pose
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import STYLES
from lfdfuse.sources.teachers import NetworkTeacher, TeacherParams, teacher_from
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
    duration: float = duration_option(300.0, "--duration", "-d", help="Maximum simulated time in seconds."),
    seed: int = seed_option("Seed of every random draw (teacher noise, sensor noise)."),
    start: str | None = start_option(),
    noise: float = sensor_noise_option(),
    heading_noise: float | None = typer.Option(
        None,
        "--heading-noise",
        min=0.0,
        max=180.0,
        callback=finite,
        help="Teacher heading noise std in degrees (default 5; correlated for style teachers).",
    ),
    keys: float | None = typer.Option(
        None,
        "--keys",
        min=0.1,
        max=60.0,
        callback=finite,
        help="The teacher as a person at a keyboard: the nearest teleop key every KEYS seconds (jittered), held.",
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
      lfdfuse simulate --teacher fusion.yaml --heading-noise 5 -o truth.mcap
      lfdfuse simulate --teacher task.yaml --keys 0.5 -o keys.mcap
    """
    check_outputs([out], [existing(world), existing(teacher)])
    w = load_world(world)
    pose = Pose.parse(start) if start is not None else None
    spec = teacher_from(teacher, w)
    tp = TeacherParams()
    if heading_noise is not None:
        tp = replace(tp, heading_noise_rad=math.radians(heading_noise))
    if isinstance(spec, NetworkTeacher):
        if keys is not None:
            raise ConfigError("--keys needs a style or task teacher, not a fusion table")
        eopts = ExecuteOptions(
            world=w,
            table=parse_table(spec.data),
            table_name=spec.name,
            start=pose,
            max_time_s=duration,
            seed=seed,
            heading_noise_rad=tp.heading_noise_rad,
            sensor_noise_m=noise,
        )
        with progress_bar("simulate") as update:
            res = run_table(eopts, out=out, command="simulate", teacher=True, progress=update)
        print_run(res.summary, title=f"simulate {w.name} / network teacher {spec.name}")
        return
    opts = SimulateOptions(
        world=w,
        legs=list(spec.legs),
        teacher_name=spec.name,
        duration_s=duration,
        seed=seed,
        start=pose,
        sensor_noise_m=noise,
        teacher=tp,
        keys_period_s=keys,
    )
    with progress_bar("simulate") as update:
        summary = simulate(opts, out=out, progress=update)
    print_run(
        summary,
        title=f"simulate {w.name} / {spec.name}" + ("" if keys is None else f" at a keyboard ({keys:g} s)"),
    )
