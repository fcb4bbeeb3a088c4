"""``lfdfuse record``: a live robot driven by a person's own teleop, recorded as an lfdfuse demo."""

from __future__ import annotations

from pathlib import Path

import typer

from lfdfuse.cli.app import app
from lfdfuse.cli.common import check_outputs, console, err_console, user_errors
from lfdfuse.cli.drive import robot_url
from lfdfuse.cli.import_cmd import print_summary as print_import
from lfdfuse.drive.options import Stopper
from lfdfuse.record import RecordOptions, record


@app.command("record")
@user_errors
def record_cmd(
    out: Path = typer.Option(
        ..., "--out", "-o", help="The demo to write (MCAP), as `lfdfuse import` writes it."
    ),
    ros2: bool = typer.Option(
        False, "--ros2", help="Listen to the robot's ROS 2 network over DDS (no bridge, no ROS install)."
    ),
    domain: int | None = typer.Option(
        None, "--domain", min=0, max=232, help="--ros2: the DDS domain (default: ROS_DOMAIN_ID, else 0)."
    ),
    connect: str | None = typer.Option(
        None, "--connect", help="Or the robot's Foxglove WebSocket server, ws://HOST:PORT (foxglove_bridge)."
    ),
    scan: str = typer.Option("/scan", "--scan", help="Laser scan topic."),
    odom: str = typer.Option("/odom", "--odom", help="Odometry topic."),
    cmd: str = typer.Option("/cmd_vel", "--cmd", help="The velocity commands the person's teleop publishes."),
    duration: float | None = typer.Option(
        None,
        "--duration",
        min=0.1,
        max=86_400.0,
        help="Stop after this many seconds (default: until Ctrl-C or SIGTERM).",
    ),
) -> None:
    """Record a demonstration from a live robot while a person drives it with their own teleop.

    Publishes nothing: it listens to the scan, odometry, tf and the commands on --cmd (from
    teleop_twist_keyboard, a joystick, Foxglove's Teleop panel …) and, when stopped (Ctrl-C,
    SIGTERM, --duration), writes them as `lfdfuse import` writes a bag — the same channels and
    provenance, teacher: human — so `lfdfuse segment` takes the file directly.

    --ros2 reads ROS 2's DDS topics (rt/scan, rt/odom, rt/tf, rt/tf_static, rt/cmd_vel) with the
    QoS ROS 2 publishers use; network settings are Cyclone DDS's (CYCLONEDDS_URI).

    Examples:
      lfdfuse record --ros2 -o demo.mcap --duration 300
      lfdfuse record --ros2 --domain 7 --cmd /teleop/cmd_vel -o demo.mcap
      lfdfuse record --connect ws://robot:8765 -o demo.mcap
    """
    url = robot_url(connect=connect, ros2=ros2, domain=domain)
    check_outputs([out], [])
    opts = RecordOptions(url=url, scan_topic=scan, odom_topic=odom, cmd_topic=cmd, duration_s=duration)
    err_console.print(f"record {url} → {out} (publishing nothing; Ctrl-C ends and writes)", markup=False)
    s = record(
        opts,
        out=out,
        notify=lambda line: err_console.print(line, markup=False, soft_wrap=True),
        stopper=Stopper(),
    )
    got = ", ".join(f"{n} {role}" for role, n in sorted(s.received.items())) or "nothing"
    console.print(f"record: received {got}; ended {s.ended}; {s.connections} connection(s)", markup=False)
    print_import(s.demo, console=console)
