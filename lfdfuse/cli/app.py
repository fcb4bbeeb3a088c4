"""The typer application every command registers on, and what commands share."""

from __future__ import annotations

from pathlib import Path

import typer

from lfdfuse.world.model import DEFAULT_WORLD

app = typer.Typer(
    name="lfdfuse",
    help="Learn behaviour fusion from one demonstration: simulate | segment | estimate | execute.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


WORLD_HELP = f"A built-in world name (see `lfdfuse worlds`) or a world YAML path. Default: {DEFAULT_WORLD}."


def default_out(src: Path, suffix: str) -> Path:
    name = src.name[:-5] if src.name.endswith(".mcap") else src.name
    return src.with_name(f"{name}{suffix}.mcap")
