"""``lfdfuse import``: a real robot log into an lfdfuse demo."""

from __future__ import annotations

import math
from enum import StrEnum
from pathlib import Path

import typer
from rich.console import Console

from lfdfuse.cli.app import app
from lfdfuse.cli.common import console, positive, user_errors
from lfdfuse.robot.mount import Mount
from lfdfuse.sources.importers.convert import CmdFrom, ImportOptions, ImportSummary, import_log
from lfdfuse.sources.importers.goals import read_goals
from lfdfuse.sources.importers.records import TopicChoice


class Format(StrEnum):
    """``--format``: the importers of :data:`lfdfuse.sources.importers.FORMATS` (a test keeps
    the two the same)."""

    ROS1 = "ros1"
    ROS2 = "ros2"
    CARMEN = "carmen"
    BREEZYSLAM = "breezyslam"


class CmdSource(StrEnum):
    """``--cmd-from``: where the demo's commands come from (:data:`CmdFrom`)."""

    AUTO = "auto"
    CMD = "cmd"
    ODOM = "odom"


class Driver(StrEnum):
    """``--teacher``: who drove, for provenance."""

    HUMAN = "human"
    UNKNOWN = "unknown"


_CMD_FROM: dict[CmdSource, CmdFrom] = {CmdSource.AUTO: "auto", CmdSource.CMD: "cmd", CmdSource.ODOM: "odom"}


def parse_mount(text: str) -> Mount:
    """``X,Y,YAW`` (m, m, rad) into a :class:`Mount`; a bad value is a usage error."""
    try:
        x, y, yaw = (float(v) for v in text.split(","))
    except ValueError:
        raise typer.BadParameter(
            f"expected X,Y,YAW in m, m, rad (e.g. -0.1,0,3.1416), got {text!r}"
        ) from None
    return Mount(x, y, yaw)


def default_out(src: Path) -> Path:
    name = src.name.rstrip("/")
    for suffix in (".gz", ".mcap", ".bag", ".db3", ".clf", ".log", ".dat"):
        name = name.removesuffix(suffix)
    return Path(f"{name}.demo.mcap")


@app.command("import")
@user_errors
def import_cmd(
    source: Path = typer.Argument(
        ...,
        help="A robot log: ROS 2 bag (MCAP, rosbag2 folder, .db3), ROS 1 .bag, CARMEN log, BreezySLAM .dat.",
    ),
    out: Path | None = typer.Option(
        None, "--out", "-o", help="Output demo MCAP (default: NAME.demo.mcap here)."
    ),
    fmt: Format | None = typer.Option(None, "--format", "-f", help="Source format; default: detected."),
    scan: str | None = typer.Option(
        None, "--scan", help="Laser scan topic (default: /scan or the busiest one)."
    ),
    cmd: str | None = typer.Option(
        None, "--cmd", help="Velocity command topic (default: /cmd_vel or the busiest)."
    ),
    odom: str | None = typer.Option(None, "--odom", help="Odometry topic (default: /odom or the busiest)."),
    cmd_publisher: str | None = typer.Option(
        None,
        "--cmd-publisher",
        help="Keep only the commands this node published (ROS 1 callerid, e.g. /teleop_twist_keyboard); "
        "default: every publisher's, merged in time order.",
    ),
    cmd_from: CmdSource = typer.Option(
        CmdSource.AUTO,
        "--cmd-from",
        help="cmd: the recorded commands; odom: commands derived from odometry; auto: cmd when the log has any.",
    ),
    goals: Path | None = typer.Option(
        None, "--goals", help="YAML list of goal times ({t: 12.5}) or positions ({x: 3, y: -1})."
    ),
    laser_mount: str | None = typer.Option(
        None, "--laser-mount", help="Laser mounting X,Y,YAW on the robot (m, m, rad); default: from the log."
    ),
    v_max: float | None = typer.Option(
        None, "--v-max", callback=positive, help="Robot speed limit (m/s); default: from the log."
    ),
    omega_max: float | None = typer.Option(
        None, "--omega-max", callback=positive, help="Robot turn-rate limit (rad/s); default: from the log."
    ),
    teacher: Driver = typer.Option(Driver.UNKNOWN, "--teacher", help="Who drove (provenance)."),
) -> None:
    """Turn a real robot log into an lfdfuse demo: /scan, /cmd_vel, /pose and provenance.

    Scans keep the scanner's real beam geometry, turned into the robot's frame by the laser's
    mounting (from /tf_static, the log's parameters, or --laser-mount); inf, NaN, 0 and max-range
    readings become no return. Commands are held until the next; a log without commands (or
    --cmd-from odom) gets commands derived from successive poses.

    Examples:
      lfdfuse import turtlebot-bag.mcap -o turtlebot.mcap
      lfdfuse import neato.bag --teacher human -o neato.mcap
      lfdfuse import intel-corrected.log.gz -o intel.mcap
      lfdfuse import run.bag --scan /base_scan --cmd-from odom --goals goals.yaml
      lfdfuse import wall_follow.bag --cmd-publisher /wall_follow
    """
    opts = ImportOptions(
        fmt=None if fmt is None else fmt.value,
        topics=TopicChoice(scan, cmd, odom, cmd_publisher),
        cmd_from=_CMD_FROM[cmd_from],
        mount=parse_mount(laser_mount) if laser_mount else None,
        v_max_mps=v_max,
        omega_max_rps=omega_max,
        teacher="human" if teacher is Driver.HUMAN else "unknown",
        goals=read_goals(goals) if goals else (),
    )
    summary = import_log(source, out=out or default_out(source), options=opts)
    print_summary(summary, console=console, given=TopicChoice(scan, cmd, odom))


def print_summary(s: ImportSummary, *, console: Console, given: TopicChoice = TopicChoice()) -> None:
    """The human summary of an import: what was picked, every count, what was dropped and why."""
    g = s.geometry
    named = {"scan": given.scan, "cmd": given.cmd, "odom": given.odom}
    topics = ", ".join(
        f"{role} {name}" + ("" if named.get(role) else " (picked)") for role, name in s.topics.items()
    )
    fov = math.degrees(abs(g.increment_rad) * g.count)
    console.print(f"[bold]import[/bold] {s.source} ({s.format}) → {s.out}")
    console.print(f"  topics: {topics}")
    console.print(
        f"  laser: {g.count} beams over {fov:.1f}° from {math.degrees(g.start_rad):+.1f}° (robot frame), "
        f"max range {g.max_range_m:g} m, {100 * s.no_return_fraction:.1f}% no return"
    )
    console.print(f"  mounting: {s.mount.describe()} ({s.mount_from})")
    console.print(
        f"  scans {s.scans}, commands {s.commands} ({s.commands_from}), poses {s.poses}; {s.duration_s:.1f} s"
    )
    v = "unknown" if s.v_max_mps is None else f"{s.v_max_mps:.3g} m/s"
    w = "unknown" if s.omega_max_rps is None else f"{s.omega_max_rps:.3g} rad/s"
    console.print(f"  robot limits: v_max {v}, ω_max {w} ({s.limits_from})")
    if s.command_model is not None:
        console.print(f"  commands: {s.command_model.describe()}")
    if s.publishers:
        kept = "" if s.cmd_publisher is None else f" (kept {s.cmd_publisher})"
        console.print(f"  publishers on {s.topics.get('cmd', '/cmd_vel')}{kept}:")
        for pub in s.publishers:
            first, last = ((t - s.start_ns) / 1e9 for t in (pub.first_ns, pub.last_ns))
            count = f"{pub.count} message{'s' if pub.count != 1 else ''}"
            console.print(f"    {pub.name}: {count}, {first:.1f}–{last:.1f} s")
    if s.goals:
        console.print(f"  goals: {', '.join(s.goals)}")
    if not s.dropped:
        console.print("  dropped: none")
    else:
        console.print(f"  dropped: {sum(s.dropped.values())}")
        for reason, n in s.dropped.items():
            console.print(f"    {n:>6}  {reason}")
    for note in s.notes:
        console.print(f"  note: {note}")
