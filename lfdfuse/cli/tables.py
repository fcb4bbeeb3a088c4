"""Tables on the console, never with a cut cell.

Piped, a table is printed whole at its own width (a file has no screen to fit). On a terminal
narrower than the table, its columns are shown in groups that fit, each led again by the first
column (what the row is); a header may wrap between its words, a number is never cut.
"""

from __future__ import annotations

import re

from rich.cells import cell_len
from rich.console import Console, RenderableType
from rich.measure import Measurement
from rich.table import Column, Table
from rich.text import Text

from lfdfuse.cli.common import PipedConsole, console


def show(table: Table) -> None:
    """Print ``table`` on stdout (see the module docstring)."""
    if not console.is_terminal:
        need = Measurement.get(console, console.options.update_width(10_000), table).maximum
        # console.print(width=) never exceeds the console's own width: a console as wide as the table
        PipedConsole(highlight=False, width=max(console.width, need)).print(table)
        return
    for i, part in enumerate(fitted(table, console.width)):
        if i:
            console.print()
        console.print(part)


def _text(cell: RenderableType) -> str:
    return cell.plain if isinstance(cell, Text) else str(cell)


def _need(column: Column, padding: int) -> int:
    """The narrowest the column can be with every cell whole and its header wrapped at words."""
    cells = [_text(c) for c in column.cells]
    header = re.findall(r"^\s*\S+|\S+", _text(column.header)) or [""]  # leading blanks stay
    return max(cell_len(w) for w in [*cells, *header]) + padding


def _natural(table: Table) -> int:
    wide = Console(width=10_000)
    return Measurement.get(wide, wide.options, table).maximum


def fitted(table: Table, width: int) -> list[Table]:
    """``table`` as one table when it fits ``width``, else its columns in groups that each fit,
    the first column repeated in every group (a column wider than the screen stands alone)."""
    columns = table.columns
    pad = table.padding[1] + table.padding[3]
    if _natural(table) <= width or len(columns) < 3:
        return [table]
    need = [_need(c, pad) for c in columns]
    groups: list[list[int]] = []
    current: list[int] = []
    room = width - need[0]
    for i in range(1, len(columns)):
        if current and need[i] > room:
            groups.append(current)
            current, room = [], width - need[0]
        current.append(i)
        room -= need[i]
    groups.append(current)
    parts = []
    for k, group in enumerate(groups):
        part = Table(
            box=table.box,
            header_style=table.header_style,
            padding=table.padding,
            pad_edge=table.pad_edge,
            title=table.title if k == 0 else None,
            title_justify=table.title_justify,
        )
        for i in (0, *group):
            c = columns[i]
            part.add_column(c.header, justify=c.justify, no_wrap=c.no_wrap)
        cells = [list(columns[i].cells) for i in (0, *group)]
        for row in zip(*cells, strict=True):
            part.add_row(*row)
        if _natural(part) > width:  # headers wrap at their words in columns as narrow as can be
            for j, i in enumerate((0, *group)):
                part.columns[j].width = need[i] - pad
        parts.append(part)
    return parts
