"""``lfdfuse inspect``."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from lfdfuse.cli.app import app
from lfdfuse.cli.common import console, user_errors
from lfdfuse.cli.render import print_changes, print_provenance, print_segments, print_subgoals, print_table
from lfdfuse.errors import ConfigError
from lfdfuse.files import YamlKind, kind_of, read_yaml
from lfdfuse.log.messages import PROVENANCE
from lfdfuse.log.reader import file_info
from lfdfuse.network.table import parse_table
from lfdfuse.segment.pipeline import step_s_of
from lfdfuse.segment.read import read_segmented, segmentation_of
from lfdfuse.sources.tasks import parse_task
from lfdfuse.world.model import load_world


@app.command()
@user_errors
def inspect(
    file: Path = typer.Argument(
        ..., help="An MCAP file (an lfdfuse log or a ROS 2 bag), or a world, task or table YAML."
    ),
) -> None:
    """Summarise a file: an MCAP's channels, message counts, duration and provenance; a world's
    walls, targets and start; a task's legs; a fusion table's network.

    Examples:
      lfdfuse inspect demo.mcap
      lfdfuse inspect fusion.yaml
    """
    if file.suffix in (".yaml", ".yml"):
        _inspect_yaml(file)
        return
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
        if name == PROVENANCE:
            console.print(
                f"  metadata [bold]{name}[/bold]: " + ", ".join(f"{k}={_short(v)}" for k, v in data.items())
            )
        else:
            # a foreign record (rosbag2's is a whole YAML document): its keys, not its contents
            keys = ", ".join(_short(k, 30) for k in list(data)[:8]) + (", …" if len(data) > 8 else "")
            console.print(f"  metadata [bold]{_short(name, 40)}[/bold]: {len(data)} key(s) ({keys})")
    if PROVENANCE not in info.metadata:
        console.print("  not written by lfdfuse: run `lfdfuse import` on it to get a demo")
    if info.attachments:
        console.print(f"  attachments: {', '.join(_short(a, 40) for a in info.attachments)}")
    if "/lfd/segment" in info.channels and "/lfd/behaviors" in info.channels:
        seg = read_segmented(file)
        console.print(f"  segmented with: {', '.join(seg.names)}")
        net = seg.metadata.get("segment_network_ticks")
        if net is not None:  # a correction log: only the person's ticks teach
            console.print(f"  correction log: {net} tick(s) the network drove are not informative")
        print_segments(segmentation_of(seg), seg.names, step_s_of(seg.t_ns))


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
            print_subgoals(table)  # sub-goals at decision points, in words (issue 15)
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
