"""``lfdfuse inspect``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer
from rich.table import Table

from lfdfuse.cli.app import app
from lfdfuse.cli.common import console, user_errors
from lfdfuse.cli.render import print_segments
from lfdfuse.log.reader import file_info
from lfdfuse.segment.read import read_segmented, segmentation_of


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
        print_segments(segmentation_of(seg), seg.names, dt)
