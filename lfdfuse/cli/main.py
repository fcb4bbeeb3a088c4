"""``lfdfuse``: simulate, segment, estimate and execute learned behaviour fusion."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import typer
import yaml
from rich.table import Table

from lfdfuse.behaviors.primitives import DEFAULT_PRESET, PRESETS
from lfdfuse.cli.common import console, progress_bar, user_errors
from lfdfuse.errors import ConfigError
from lfdfuse.estimate.pf import PFParams
from lfdfuse.estimate.pipeline import METHODS, EstimateOptions, estimate_file
from lfdfuse.execute.run import ExecuteOptions, drive_table, verdict, write_report
from lfdfuse.log.reader import file_info
from lfdfuse.network.table import FusionTable, Network, load_table
from lfdfuse.segment.pipeline import Segmentation, bac_summary, read_segmented, segment_file, segmentation_of
from lfdfuse.sim.robot import Pose
from lfdfuse.sources.simulate import RunSummary, SimulateOptions, simulate
from lfdfuse.sources.teachers import STYLES, Leg, TeacherParams, load_task, parse_style
from lfdfuse.world.model import DEFAULT_WORLD, load_world, world_descriptions

app = typer.Typer(
    name="lfdfuse",
    help="Learn behaviour fusion from one demonstration: simulate | segment | estimate | execute.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

WORLD_HELP = f"A built-in world name (see `lfdfuse worlds`) or a world YAML path. Default: {DEFAULT_WORLD}."


@app.command()
@user_errors
def worlds() -> None:
    """List the built-in worlds with a one-line description.

    Example: lfdfuse worlds
    """
    table = Table(show_header=True, header_style="bold", box=None)
    table.add_column("world")
    table.add_column("description")
    for name, desc in world_descriptions():
        table.add_row(name, desc)
    console.print(table)


def _print_run(summary: RunSummary, *, title: str) -> None:
    console.print(f"[bold]{title}[/bold] → {summary.out}")
    console.print(f"  duration   {summary.duration_s:8.1f} s   ({summary.steps} steps)")
    console.print(f"  distance   {summary.distance_m:8.1f} m")
    console.print(f"  collisions {summary.collisions:8d}")
    reached = ", ".join(f"{n} at {t:.1f} s" for n, t in summary.reached) or "none"
    console.print(f"  targets    {reached}")
    console.print(
        f"  side range left {summary.left_range_mean_m:.2f} m, right {summary.right_range_mean_m:.2f} m (mean at ±90°)"
    )


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
    w = load_world(world)
    pose = Pose.parse(start) if start else None
    if teacher.endswith((".yaml", ".yml")) or Path(teacher).is_file():
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
            _print_run(res.summary, title=f"simulate {w.name} / network teacher {Path(teacher).name}")
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
    _print_run(summary, title=f"simulate {w.name} / {name}")


def is_fusion_table(path: Path) -> bool:
    """A YAML whose top level has ``format:`` is a fusion table (a network teacher)."""
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError):
        return False
    return isinstance(data, dict) and "format" in data


@app.command()
@user_errors
def inspect(file: Path = typer.Argument(..., help="Any MCAP file: an lfdfuse log or a ROS 2 bag.")) -> None:
    """Print the channels, message counts, duration and metadata of an MCAP file.

    Example: lfdfuse inspect demo.mcap
    """
    info = file_info(file)
    dur = (info.end_ns - info.start_ns) / 1e9 if info.end_ns else 0.0
    console.print(f"[bold]{file}[/bold]  ({info.library or 'unknown writer'})")
    console.print(f"  duration {dur:.1f} s, {sum(c for _, _, c in info.channels.values())} messages")
    table = Table(box=None, header_style="bold")
    table.add_column("topic")
    table.add_column("schema")
    table.add_column("encoding")
    table.add_column("messages", justify="right")
    for topic, (schema, enc, count) in info.channels.items():
        table.add_row(topic, schema, enc, str(count))
    console.print(table)
    for name, data in info.metadata.items():
        console.print(
            f"  metadata [bold]{name}[/bold]: " + ", ".join(f"{k}={v}" for k, v in data.items()), markup=True
        )
    if info.attachments:
        console.print(f"  attachments: {', '.join(info.attachments)}")
    if "/lfd/segment" in info.channels and "/lfd/behaviors" in info.channels:
        seg = read_segmented(file)
        dt = float(np.median(np.diff(seg.t_ns))) / 1e9 if len(seg.t_ns) > 1 else 0.1
        console.print(f"  segmented with: {', '.join(seg.names)}")
        _print_segments(segmentation_of(seg), seg.names, dt)


def default_out(src: Path, suffix: str) -> Path:
    name = src.name[:-5] if src.name.endswith(".mcap") else src.name
    return src.with_name(f"{name}{suffix}.mcap")


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
    _print_segments(res.segmentation, res.names, dt)


def _print_segments(segm: Segmentation, names: tuple[str, ...], dt: float) -> None:
    for seg in segm.segments:
        bacs = bac_summary(segm, seg)
        goal = seg.goal or "no goal reached"
        steps = seg.stop - seg.start
        console.print(
            f"  [bold]segment {seg.index}[/bold] → {goal}: {steps * dt:.1f} s, {steps} steps, {len(bacs)} BACs"
        )
        cells = [f"{b} ({n})" for b, n, _ in bacs]
        console.print("    BAC (samples): " + ", ".join(cells), soft_wrap=False)


_SHORT = {
    "avoid": "av",
    "wander": "w",
    "wander_left": "wL",
    "wander_right": "wR",
    "wall_attract": "a",
    "wall_attract_left": "aL",
    "wall_attract_right": "aR",
    "sonar_avoid": "son",
    "wall_side_left": "sL",
    "wall_side_right": "sR",
    "circular_avoid_left": "cL",
    "circular_avoid_right": "cR",
}


def _abbrev(name: str) -> str:
    return _SHORT.get(name, name.replace("attract_", ""))


def print_table(table: FusionTable) -> None:
    """Weights (± std), samples and fit error per step and BAC, in percent to fit a terminal."""
    legend = ", ".join(f"{_abbrev(b)}={b}" for b in table.behaviors)
    console.print(
        f"weights and std in % of the row; n = samples (* = too few to trust); fit° = mean heading error\n{legend}"
    )

    def walk(net: Network, depth: int) -> None:
        for step in net.steps:
            goal = f"goal {step.goal}" if step.goal else "no goal"
            console.print(f"{'  ' * depth}[bold]{step.name}[/bold] ({goal})")
            if step.network is not None:
                walk(step.network, depth + 1)
                continue
            t = Table(box=None, header_style="bold", pad_edge=False, padding=(0, 1))
            t.add_column("BAC", justify="right")
            t.add_column("n", justify="right")
            t.add_column("fit°", justify="right")
            for b in table.behaviors:
                t.add_column(_abbrev(b), justify="right")
            for row in sorted(step.fusion, key=lambda r: -(r.samples or 0)):
                cells = []
                for b in table.behaviors:
                    if b in row.weights:
                        sd = (row.std or {}).get(b)
                        cells.append(
                            f"{100 * row.weights[b]:.0f}" + (f"±{100 * sd:.0f}" if sd is not None else "")
                        )
                    else:
                        cells.append("")
                n = f"{row.samples}" + ("*" if row.low_samples else "") if row.samples is not None else ""
                fit = f"{row.fit_error_deg:.1f}" if row.fit_error_deg is not None else ""
                t.add_row(str(row.bac), n, fit, *cells)
            if step.fusion:
                console.print(t)
            else:
                console.print("    (no informative steps: default weights)")

    walk(table.network, 0)


@app.command("estimate")
@user_errors
def estimate_cmd(
    src: Path = typer.Argument(..., help="A segmented log (from `lfdfuse segment`)."),
    method: str = typer.Option(
        "pf",
        "--method",
        "-m",
        help="pf (particle filter), nnls (least squares) or arbitration (best single behaviour).",
    ),
    particles: int = typer.Option(PFParams().particles, "--particles", help="Particles per filter (pf)."),
    trials: int = typer.Option(
        1,
        "--trials",
        "-k",
        help="Independent filters (pf) or bootstrap fits (nnls, arbitration); mean and std are reported.",
    ),
    likelihood: str = typer.Option(
        "vonmises", "--likelihood", help="pf likelihood: vonmises (default) or paper (2 - D/2)."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the filters' random draws."),
    out: Path = typer.Option(Path("fusion.yaml"), "--out", "-o", help="Output fusion table (YAML)."),
) -> None:
    """Estimate fusion weights per goal segment and BAC, and write the behaviour network.

    Rows marked * have fewer samples than can be trusted (low_samples in the YAML).

    Examples:
      lfdfuse estimate demo.seg.mcap
      lfdfuse estimate demo.seg.mcap --trials 30 -o fusion.yaml
      lfdfuse estimate demo.seg.mcap --method nnls -o nnls.yaml
    """
    if method not in METHODS:
        raise ConfigError(f"unknown method {method!r} (valid: {', '.join(METHODS)})")
    if likelihood not in ("vonmises", "paper"):
        raise ConfigError(f"unknown likelihood {likelihood!r} (valid: vonmises, paper)")
    pf = replace(PFParams(), particles=particles, likelihood=likelihood)  # type: ignore[arg-type]
    opts = EstimateOptions(method=method, trials=trials, seed=seed, pf=pf)  # type: ignore[arg-type]
    with progress_bar("estimate") as update:
        res = estimate_file(src, out=out, opts=opts, progress=update)
    console.print(
        f"[bold]estimate[/bold] {src} → {res.out}  ({method}, {trials} trial{'s' if trials > 1 else ''}, {res.groups} groups)"
    )
    print_table(res.table)


@app.command("execute")
@user_errors
def execute_cmd(
    table: Path = typer.Argument(
        ..., help="A fusion table YAML (from `lfdfuse estimate`, or written by hand)."
    ),
    world: str = typer.Option(DEFAULT_WORLD, "--world", "-w", help=WORLD_HELP),
    start: str | None = typer.Option(
        None, "--start", help="Start pose X,Y,THETA (m, m, rad); default: the world's."
    ),
    max_time: float = typer.Option(300.0, "--max-time", help="Stop after this many simulated seconds."),
    seed: int = typer.Option(0, "--seed", help="Seed of every random draw (sensor noise)."),
    noise: float = typer.Option(
        0.0, "--sensor-noise", help="Std (m) of Gaussian range noise on laser and sonar."
    ),
    stop_on_collision: bool = typer.Option(
        False, "--stop-on-collision", help="End the run at the first collision."
    ),
    out: Path = typer.Option(
        Path("run.mcap"), "--out", "-o", help="Run log (MCAP) with the /lfd/* channels and an overlay."
    ),
    report: Path | None = typer.Option(None, "--report", help="Write the JSON report here."),
) -> None:
    """Let a learned behaviour network drive the robot, log the run and report how it went.

    The run stops when the last goal is achieved or at --max-time.

    Examples:
      lfdfuse execute fusion.yaml --world building -o run.mcap --report run.json
      lfdfuse execute fusion.yaml --world tee --start 1,9,0 --max-time 120
    """
    w = load_world(world)
    tab = load_table(table)
    pose = Pose.parse(start) if start else None
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
        res = drive_table(opts, out=out, command="execute", progress=update)
    if report is not None:
        write_report(res.report, report)
    print_report(res.report, out=str(out))


def print_report(rep: dict[str, Any], *, out: str) -> None:
    status = "task completed" if rep["completed"] else "task not completed"
    console.print(
        f"[bold]execute[/bold] → {out}: {status} in {rep['duration_s']:.1f} s, {rep['path_length_m']:.1f} m, {rep['collisions']} collisions"
    )
    for g in rep["goals"]:
        when = f"at {g['time_s']:.1f} s" if g["reached"] else "not reached"
        console.print(f"  goal {g['name']} ({g['target']}): {when}")
    for s in rep["steps"]:
        console.print(
            f"  step {s['name']}: side range left {s['left_range_mean_m']:.2f} m, right {s['right_range_mean_m']:.2f} m"
        )
    console.print(
        f"  overall: left {rep['left_range_mean_m']:.2f} m, right {rep['right_range_mean_m']:.2f} m; default weights on {100 * rep['unseen_bac_fraction']:.1f}% of ticks"
    )
    console.print(f"  [bold]verdict[/bold]: {verdict(rep)}")


def main() -> None:
    app()


if __name__ == "__main__":
    main()
