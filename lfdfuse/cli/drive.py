"""``lfdfuse drive``: the learned network drives a live robot (Foxglove WebSocket, or ROS 2 over DDS)."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from lfdfuse.cli.app import app
from lfdfuse.cli.common import check_outputs, console, err_console, user_errors
from lfdfuse.drive.options import DriveOptions, DriveSummary
from lfdfuse.drive.ros2.url import domain_id, ros2_url
from lfdfuse.drive.session import drive
from lfdfuse.network.table import load_table
from lfdfuse.words import counted


@app.command("drive")
@user_errors
def drive_cmd(
    table: Path = typer.Argument(..., help="A fusion table YAML (from `lfdfuse estimate`)."),
    connect: str | None = typer.Option(
        None,
        "--connect",
        help="The robot's Foxglove WebSocket server, ws://HOST:PORT (foxglove_bridge, or `lfdfuse teleop --input foxglove`).",
    ),
    ros2: bool = typer.Option(
        False,
        "--ros2",
        help="Join the robot's ROS 2 network over DDS instead (no bridge, no ROS install): topic /scan is the DDS topic rt/scan.",
    ),
    domain: int | None = typer.Option(
        None,
        "--domain",
        min=0,
        max=232,
        help="--ros2: the DDS domain (ROS_DOMAIN_ID; default: that variable, else 0).",
    ),
    scan: str = typer.Option("/scan", "--scan", help="Laser scan topic."),
    odom: str = typer.Option(
        "/odom", "--odom", help="Odometry topic (else the first odometry-like channel, e.g. /pose)."
    ),
    cmd: str = typer.Option("/cmd_vel", "--cmd", help="Velocity command topic (a geometry_msgs Twist)."),
    shadow: bool = typer.Option(
        False,
        "--shadow",
        help="Publish nothing: record what the network would command beside the robot's own --cmd, and print their agreement.",
    ),
    max_speed: float | None = typer.Option(
        None,
        "--max-speed",
        min=0.01,
        max=10.0,
        help="Clamp the forward speed to this (m/s); default: the table's robot.",
    ),
    max_turn: float | None = typer.Option(
        None,
        "--max-turn",
        min=0.01,
        max=20.0,
        help="Clamp the turn rate to this (rad/s); default: the table's robot.",
    ),
    duration: float | None = typer.Option(
        None,
        "--duration",
        min=0.1,
        max=86_400.0,
        help="Stop after this many seconds (default: until Ctrl-C or SIGTERM).",
    ),
    out: Path | None = typer.Option(
        None, "--out", "-o", help="Record the live run (MCAP): sensors received, /lfd/*, commands sent."
    ),
) -> None:
    """Run a learned behaviour network live on a robot, at the robot's scan rate.

    Try --shadow first: the robot is driven by a person (or its own controller) and drive
    only reports how well the network agrees. A zero Twist is sent when scans stop for 0.5 s
    and on every exit (Ctrl-C, SIGTERM, --duration, an error); a lost connection is retried
    with back-off while --duration lasts, and a new connection starts with a zero Twist.

    --ros2 speaks ROS 2's DDS directly: it reads --scan and --odom (best effort), /tf and
    /tf_static (transient local) and publishes a reliable geometry_msgs/msg/Twist (TwistStamped
    when the robot's --cmd subscriber has that type) on --cmd; network settings are Cyclone
    DDS's (CYCLONEDDS_URI), as for a ROS 2 node using rmw_cyclonedds.

    Examples:
      lfdfuse drive fusion.yaml --connect ws://robot:8765 --shadow -o shadow.mcap
      lfdfuse drive t.yaml --connect ws://robot:8765 --max-speed 0.2 -o live.mcap
      lfdfuse drive t.yaml --connect ws://localhost:8765 --duration 60
      lfdfuse drive t.yaml --ros2 --domain 7 --shadow -o shadow.mcap
    """
    url = robot_url(connect=connect, ros2=ros2, domain=domain)
    check_outputs([out], [table])
    tab = load_table(table)
    opts = DriveOptions(
        table=tab,
        url=url,
        table_name=table.name,
        scan_topic=scan,
        odom_topic=odom,
        cmd_topic=cmd,
        shadow=shadow,
        max_speed=max_speed,
        max_turn=max_turn,
        duration_s=duration,
    )
    err_console.print(
        f"drive {table.name} → {url}" + (" (shadow: publishing nothing)" if shadow else ""), markup=False
    )
    summary = drive(opts, out=out, notify=lambda line: err_console.print(line, markup=False, soft_wrap=True))
    print_summary(summary, shadow=shadow)


def robot_url(*, connect: str | None, ros2: bool, domain: int | None) -> str:
    """The robot the options name: ``--connect URL`` or ``--ros2 [--domain N]`` (exactly one)."""
    if ros2 == (connect is not None):  # bad usage (exit 2), as a missing option is
        raise typer.BadParameter("give either --connect ws://HOST:PORT or --ros2 [--domain N]")
    if connect is not None:
        if domain is not None:
            raise typer.BadParameter("--domain is a --ros2 option")
        return connect
    return ros2_url(domain_id(domain))


def print_summary(s: DriveSummary, *, shadow: bool) -> None:
    lat = f"p50 {s.latency_ms[0]:.2f} ms, p99 {s.latency_ms[1]:.2f} ms" if s.latency_ms else "none"
    console.print(
        f"drive: {s.ticks} ticks in {s.duration_s:.1f} s; scan → command latency {lat}", markup=False
    )
    if shadow:
        console.print("  sent        nothing (shadow)", markup=False)
        if s.agreement_deg is not None:
            console.print(
                f"  agreement   {s.agreement_deg:.1f}° mean heading error over {s.agreement_ticks} informative ticks"
                " (the network vs the robot's own commands)",
                markup=False,
            )
        else:
            console.print("  agreement   none: no informative command of the robot's own came", markup=False)
    else:
        console.print(
            f"  sent        {counted(s.sent, 'command')}"
            + (f" ({s.encoding})" if s.encoding else "")
            + f", {s.zeros} of them zero Twists",
            markup=False,
        )
    console.print(f"  odometry    {s.odometry_m:.1f} m", markup=False)
    console.print(
        f"  limits      {s.limits.v_max_mps:.2f} m/s, {math.degrees(s.limits.omega_max_rps):.0f}°/s ({s.limits_from})",
        markup=False,
    )
    if s.mount_from:
        console.print(f"  laser       {s.mount_from}", markup=False)
    for text, n in s.warnings.items():
        if n > 1:
            console.print(f"  warnings    {n}× {text}", markup=False)
    console.print(
        f"  ended       {s.ended}; {s.connections} connection{'s' if s.connections != 1 else ''}",
        markup=False,
    )
    if s.out:
        console.print(f"wrote {s.out}", markup=False)
