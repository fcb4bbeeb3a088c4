"""The typer application every command registers on, and what commands share."""

from __future__ import annotations

from pathlib import Path

import typer

from lfdfuse import __version__
from lfdfuse.world.model import DEFAULT_WORLD

app = typer.Typer(
    name="lfdfuse",
    help="Learn behaviour fusion from one demonstration: simulate | segment | estimate | execute.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _print_version(value: bool) -> None:
    if value:
        typer.echo(f"lfdfuse {__version__}")
        raise typer.Exit(0)


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_print_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Learn behaviour fusion from one demonstration: simulate | segment | estimate | execute."""


WORLD_HELP = f"A built-in world name (see `lfdfuse worlds`) or a world YAML path. Default: {DEFAULT_WORLD}."


def default_out(src: Path, suffix: str) -> Path:
    name = src.name[:-5] if src.name.endswith(".mcap") else src.name
    return src.with_name(f"{name}{suffix}.mcap")
