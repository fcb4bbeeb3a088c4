"""``lfdfuse simulate``."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

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
from lfdfuse.sources.typist import CHOICES, PERSONS, KeyboardParams
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
    person: str | None = typer.Option(
        None,
        "--person",
        help=f"The keyboard person, a named model of the zoo ({', '.join(PERSONS)}); --keys sets its period.",
        rich_help_panel="Person at a keyboard",
    ),
    reaction: float | None = typer.Option(
        None,
        "--reaction",
        min=0.0,
        max=5.0,
        callback=finite,
        help="Person: seconds between what the teacher wants and the key that answers it (default 0.2).",
        rich_help_panel="Person at a keyboard",
    ),
    choose: str | None = typer.Option(
        None,
        "--choose",
        help="Person: the key by the nearest heading ('nearest') or by thresholds on the wanted turn ('thresholds').",
        rich_help_panel="Person at a keyboard",
    ),
    thresholds: str | None = typer.Option(
        None,
        "--thresholds",
        help="Person: ARC,SPIN degrees of wanted turn beyond which an arc, a turn in place is pressed (implies --choose thresholds).",
        rich_help_panel="Person at a keyboard",
    ),
    lapse: float | None = typer.Option(
        None,
        "--lapse",
        min=0.0,
        max=1.0,
        callback=finite,
        help="Person: chance a press slips, half a wrong (neighbouring) key, half a late one.",
        rich_help_panel="Person at a keyboard",
    ),
    stop_go: float | None = typer.Option(
        None,
        "--stop-go",
        min=0.0,
        max=0.99,
        callback=finite,
        help="Person: chance a press is a stop held --pause seconds before driving on.",
        rich_help_panel="Person at a keyboard",
    ),
    pause: float | None = typer.Option(
        None,
        "--pause",
        min=0.0,
        max=60.0,
        callback=finite,
        help="Person: how long a stop-and-go stop is held (s, default 1).",
        rich_help_panel="Person at a keyboard",
    ),
    corner_cut: float | None = typer.Option(
        None,
        "--corner-cut",
        min=0.0,
        max=10.0,
        callback=finite,
        help="Person: cut corners, aiming this many metres farther along the route.",
        rich_help_panel="Person at a keyboard",
    ),
    reflex: float | None = typer.Option(
        None,
        "--reflex",
        min=0.0,
        max=5.0,
        callback=finite,
        help="Person: never hold a key driving into a wall this many metres ahead (0: no reflex; the zoo's 0.5).",
        rich_help_panel="Person at a keyboard",
    ),
    sees_turn: bool | None = typer.Option(
        None,
        "--sees-turn/--blind-turn",
        help="Person: a late key allows for how far the robot turned since (the zoo's persons do).",
        rich_help_panel="Person at a keyboard",
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
      lfdfuse simulate --teacher task.yaml --person sloppy -o sloppy.mcap
      lfdfuse simulate --teacher task.yaml --person late --lapse 0.1 -o mine.mcap
    """
    check_outputs([out], [existing(world), existing(teacher)])
    w = load_world(world)
    pose = Pose.parse(start) if start is not None else None
    spec = teacher_from(teacher, w)
    tp = TeacherParams()
    if heading_noise is not None:
        tp = replace(tp, heading_noise_rad=math.radians(heading_noise))
    model = person_model(
        person,
        reaction=reaction,
        choose=choose,
        thresholds=thresholds,
        lapse=lapse,
        stop_go=stop_go,
        pause=pause,
        corner_cut=corner_cut,
        reflex=reflex,
        sees_turn=sees_turn,
    )
    if isinstance(spec, NetworkTeacher):
        if keys is not None or model is not None:
            raise ConfigError("--keys and --person need a style or task teacher, not a fusion table")
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
        person=None if model is None else model[1],
        person_name="custom" if model is None else model[0],
    )
    with progress_bar("simulate") as update:
        summary = simulate(opts, out=out, progress=update)
    kb, at = opts.keyboard, ""
    if kb is not None:
        at = f" at a keyboard ({'' if model is None else model[0] + ', '}{kb.period_s:g} s)"
    print_run(summary, title=f"simulate {w.name} / {spec.name}{at}")


def person_model(
    name: str | None,
    *,
    reaction: float | None,
    choose: str | None,
    thresholds: str | None,
    lapse: float | None,
    stop_go: float | None,
    pause: float | None,
    corner_cut: float | None,
    reflex: float | None = None,
    sees_turn: bool | None = None,
) -> tuple[str, KeyboardParams] | None:
    """The person the options name and set (its name, ``custom`` when only set), or None when
    none of them is given (``--keys`` alone keeps its own person)."""
    given = {
        "reaction_s": reaction,
        "choice": choose,
        "lapse": lapse,
        "stop_go": stop_go,
        "pause_s": pause,
        "corner_m": corner_cut,
        "reflex_m": reflex,
        "sees_turn": sees_turn,
    }
    changes: dict[str, Any] = {k: v for k, v in given.items() if v is not None}
    if thresholds is not None:
        parts = thresholds.split(",")
        try:
            arc, spin = (float(p) for p in parts)
        except ValueError:
            raise ConfigError(f"--thresholds wants ARC,SPIN in degrees, got {thresholds!r}") from None
        if not (0.0 <= arc <= spin <= 180.0):
            raise ConfigError(f"--thresholds wants 0 ≤ ARC ≤ SPIN ≤ 180 degrees, got {thresholds!r}")
        changes |= {"arc_deg": arc, "spin_deg": spin}
        changes.setdefault("choice", "thresholds")
    if "choice" in changes and changes["choice"] not in CHOICES:
        raise ConfigError(f"--choose is one of {', '.join(CHOICES)}, got {changes['choice']!r}")
    if name is None and not changes:
        return None
    if name is not None and name not in PERSONS:
        raise ConfigError(f"no person {name!r} in the zoo; there are {', '.join(PERSONS)}")
    base = PERSONS[name] if name is not None else KeyboardParams()
    label = name if name is not None else "custom"
    if changes and name is not None:
        label += "+" + ",".join(sorted(changes))
    return label, replace(base, **changes)
