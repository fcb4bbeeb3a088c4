"""``lfdfuse inspect``."""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

import typer
from rich.table import Table

from lfdfuse.cli.app import app
from lfdfuse.cli.common import console, user_errors
from lfdfuse.cli.render import print_changes, print_provenance, print_segments, print_subgoals, print_table
from lfdfuse.cli.tables import show
from lfdfuse.errors import ConfigError
from lfdfuse.files import YamlKind, kind_of, read_yaml
from lfdfuse.log.messages import PROVENANCE
from lfdfuse.log.reader import file_info
from lfdfuse.network.table import parse_table
from lfdfuse.segment.read import read_segmented, segmentation_of
from lfdfuse.sources.importers import robot_format
from lfdfuse.sources.importers.info import ROLE_TOPICS, LogSummary, summarise
from lfdfuse.sources.importers.records import SourceError
from lfdfuse.sources.tasks import parse_task
from lfdfuse.world.model import load_world


@app.command()
@user_errors
def inspect(
    file: Path = typer.Argument(
        ...,
        help="An lfdfuse log (MCAP), a robot log (ROS 2 bag: MCAP, rosbag2 folder or .db3; ROS 1 .bag; "
        "CARMEN; BreezySLAM .dat), or a world, task or table YAML.",
    ),
) -> None:
    """Summarise a file: an MCAP's channels, message counts, duration and provenance; a robot
    log's topics, types, counts and time span (like ros2 bag info) and what import would make of
    it; a world's walls, targets and start; a task's legs; a fusion table's network.

    Examples:
      lfdfuse inspect demo.mcap
      lfdfuse inspect rosbag2_folder/
      lfdfuse inspect neato.bag
      lfdfuse inspect fusion.yaml
    """
    if file.suffix in (".yaml", ".yml"):
        _inspect_yaml(file)
        return
    if file.is_dir() and not (file / "metadata.yaml").is_file():
        raise ConfigError(
            f"{file} is a folder without a rosbag2 metadata.yaml: inspect reads an MCAP file, a bag,"
            " a rosbag2 folder or a YAML file"
        )
    fmt = robot_format(file)
    refused = None
    if fmt is not None:
        try:
            print_log_summary(summarise(file, fmt=fmt))
            return
        except SourceError as exc:
            if not (file.is_file() and file.suffix == ".mcap"):
                raise
            # an MCAP rosbags cannot read as a bag: its channels still show
            refused = str(exc).removeprefix(f"{file}: ")
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
    show(table)
    for name, data in info.metadata.items():
        if name == PROVENANCE:
            console.print(
                f"  metadata [bold]{name}[/bold]: " + ", ".join(f"{k}={_short(v)}" for k, v in data.items())
            )
        else:
            # a foreign record (rosbag2's is a whole YAML document): its keys, not its contents
            keys = ", ".join(_short(k, 30) for k in list(data)[:8]) + (", …" if len(data) > 8 else "")
            console.print(f"  metadata [bold]{_short(name, 40)}[/bold]: {len(data)} key(s) ({keys})")
    if refused is not None:
        console.print(f"  import would refuse it: {refused}")
    elif PROVENANCE not in info.metadata:
        console.print("  not written by lfdfuse: run `lfdfuse import` on it to get a demo")
    if info.attachments:
        console.print(f"  attachments: {', '.join(_short(a, 40) for a in info.attachments)}")
    if "/lfd/segment" in info.channels and "/lfd/behaviors" in info.channels:
        seg = read_segmented(file)
        console.print(f"  segmented with: {', '.join(seg.names)}")
        net = seg.metadata.get("segment_network_ticks")
        if net is not None:  # a correction log: only the person's ticks teach
            console.print(f"  correction log: {net} tick(s) the network drove are not informative")
        print_segments(segmentation_of(seg), seg.names, seg.t_ns.tolist())


def _stamp(t_ns: int) -> str:
    """A record stamp: seconds to the nanosecond, and the UTC date when it is an epoch stamp."""
    sec, ns = divmod(t_ns, 1_000_000_000)
    exact = f"{sec}.{ns:09d}"
    if t_ns < 10**17:  # before 1973: a stamp relative to the log's start, not a date
        return f"{exact} s"
    date = datetime.fromtimestamp(sec, tz=UTC).strftime("%Y-%m-%d %H:%M:%S")
    return f"{date}.{ns // 1_000_000:03d} UTC ({exact})"


def _size(n_bytes: int) -> str:
    if n_bytes < 1024:
        return f"{n_bytes} B"
    size = float(n_bytes)
    for unit in ("KiB", "MiB", "GiB"):
        size /= 1024.0
        if size < 1024.0 or unit == "GiB":
            break
    return f"{size:.1f} {unit}"


def print_log_summary(s: LogSummary) -> None:
    """A robot log like ``ros2 bag info``, then what ``lfdfuse import`` would make of it."""
    console.print(f"[bold]{s.path}[/bold]  ({s.format}: {s.storage})")
    console.print(f"  files:     {', '.join(s.files)}")
    console.print(f"  size:      {_size(s.size_bytes)}")
    console.print(f"  duration:  {s.duration_s:.1f} s")
    if s.start_ns is not None and s.end_ns is not None:
        console.print(f"  start:     {_stamp(s.start_ns)}")
        console.print(f"  end:       {_stamp(s.end_ns)}")
    console.print(f"  messages:  {s.messages} on {len(s.topics)} topic(s)")
    table = Table(box=None, header_style="bold")
    table.add_column("topic")
    table.add_column("type")
    table.add_column("messages", justify="right")
    table.add_column("serialization")
    for t in s.topics:
        table.add_row(t.topic, t.msgtype, str(t.count), t.serialization)
    show(table)
    plan = s.plan
    if plan.problem is not None:
        console.print(f"  import would refuse it: {plan.problem}")
        return
    by_topic = {t.topic: t for t in s.topics}

    def source(name: str) -> str:
        t = by_topic.get(name)
        return name if t is None else f"{name} ({t.msgtype}, {t.count})"

    console.print("  import would make:")
    for role, ours in ROLE_TOPICS.items():
        if role == "cmd":
            cmd = plan.topics.get("cmd")
            recorded = cmd is not None and plan.commands_from.startswith("recorded")
            what = f"{source(cmd)}, as recorded" if cmd and recorded else plan.commands_from
        else:
            name = plan.topics.get(role)
            what = source(name) if name else "nothing (the log has none)"
        console.print(f"    {ours:<9} ← {what}")
    mount = "unknown: assumed at the base, facing forward" if plan.mount is None else plan.mount.describe()
    console.print(f"    laser mounting {mount}" + (f" ({plan.mount_from})" if plan.mount_from else ""))
    for note in plan.notes:
        console.print(f"  note: {note}")
    console.print(f"  run `lfdfuse import {s.path} -o demo.mcap` to get a demo")


def _short(value: object, width: int = 60) -> str:
    """One line of at most ``width`` characters."""
    text = " ".join(str(value).split())
    return text if len(text) <= width else text[: width - 1] + "…"


def _inspect_yaml(file: Path) -> None:
    data = read_yaml(file, what="file")
    kind = kind_of(data)
    if kind is YamlKind.TABLE:
        table = parse_table(data)
        console.print(f"[bold]{file}[/bold]  fusion table, {len(table.behaviors)} behaviours")
        print_provenance(table)
        print_table(table)
        print_changes(table)  # pooled demos: the rows the later ones changed, before → after
        if any(s.network is not None for s in table.network.steps):
            print_subgoals(table)  # sub-goals at decision points, in words
    elif kind is YamlKind.TASK:
        legs = parse_task(data, origin=str(file))
        console.print(f"[bold]{file}[/bold]  task of {len(legs)} leg(s)")
        for i, leg in enumerate(legs):
            console.print(
                f"  {i + 1}. {'reach ' + leg.target if leg.target else 'tour'} in style {leg.style}"
            )
    elif kind is YamlKind.WORLD:
        w = load_world(str(file))  # a map_server map YAML too (it reads its image)
        x0, y0, x1, y1 = w.bounds()
        console.print(f"[bold]{file}[/bold]  world {w.name!r}: {x1 - x0:.1f} m x {y1 - y0:.1f} m")
        console.print(
            f"  {len(w.walls)} wall polylines, {len(w.obstacles)} obstacles, {len(w.segments)} segments"
        )
        targets = ", ".join(f"{t.name} ({t.x:g}, {t.y:g})" for t in w.targets) or "none"
        console.print(f"  targets: {targets}")
        console.print(f"  start: ({w.start[0]:g}, {w.start[1]:g}, {w.start[2]:g})")
    else:
        raise ConfigError(f"{file}: not a world, task or fusion table")
