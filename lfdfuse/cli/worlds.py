"""``lfdfuse worlds``."""

from __future__ import annotations

from rich.table import Table

from lfdfuse.cli.app import app
from lfdfuse.cli.common import user_errors
from lfdfuse.cli.tables import show
from lfdfuse.world.model import world_descriptions


@app.command()
@user_errors
def worlds() -> None:
    """List the built-in worlds with a one-line description.

    Example:
      lfdfuse worlds
    """
    table = Table(show_header=True, header_style="bold", box=None)
    table.add_column("world")
    table.add_column("description")
    for name, desc in world_descriptions():
        table.add_row(name, desc)
    show(table)
