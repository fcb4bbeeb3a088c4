"""The typer application every command registers on, and what commands share."""

from __future__ import annotations

import inspect
import re
from pathlib import Path
from typing import Any

import typer
from typer.core import TyperArgument, TyperCommand

from lfdfuse import __version__

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


# the default is shown once, by typer's [default: …]
WORLD_HELP = "A built-in world name (see `lfdfuse worlds`) or a world YAML path."


def help_text(doc: str) -> str:
    """A docstring as ``--help`` text that reads at any width: within a paragraph the prose lines
    are joined (the terminal wraps them, not the source's 100 columns), and indented lines
    (examples) and list items stay one per line, as written."""
    paragraphs = []
    for para in inspect.cleandoc(doc).split("\n\n"):
        lines: list[str] = []
        for line in para.splitlines():
            keep = line.startswith((" ", "- ", "* ")) or not lines or lines[-1].startswith(" ")
            if keep:
                lines.append(line)
            else:
                lines[-1] = f"{lines[-1]} {line.strip()}"
        paragraphs.append("\n".join(lines))
    # typer dedents the text after the first paragraph (inspect.cleandoc); a markup tag first on an
    # indented line keeps its indentation (and shows the example in bold)
    text = "\n\n".join(paragraphs)
    return re.sub(r"^( +)(\S.*)$", r"[bold]\1\2[/bold]", text, flags=re.M)


class Command(TyperCommand):
    """A command whose help shows arguments as SRC (not ``{src}``) and flags without ``<bool>``."""

    # typer's context and parameter classes are its own (a vendored click): typed as Any here
    def get_params(self, ctx: Any) -> list[Any]:
        params = super().get_params(ctx)
        for p in params:
            if getattr(p, "is_flag", False):
                p.metavar = ""  # a flag takes no value: nothing to show after its name
            elif isinstance(p, TyperArgument) and p.metavar is None and p.name:
                p.metavar = p.name.upper()
        return params

    def collect_usage_pieces(self, ctx: Any) -> list[str]:
        pieces = [self.options_metavar] if self.options_metavar else []
        for p in self.get_params(ctx):
            if isinstance(p, TyperArgument):
                name = (p.metavar or p.name or "") + ("..." if p.nargs != 1 else "")
                pieces.append(name if p.required else f"[{name}]")
        return pieces


def finish(typer_app: typer.Typer) -> None:
    """Give every registered command the help of its docstring (:func:`help_text`) and :class:`Command`."""
    for info in typer_app.registered_commands:
        if info.help is None and info.callback is not None and info.callback.__doc__:
            info.help = help_text(info.callback.__doc__)
        if info.cls in (None, TyperCommand):
            info.cls = Command


def default_out(src: Path, suffix: str) -> Path:
    """``IN`` with ``suffix`` before ``.mcap``, beside it (``.`` and ``..`` are named by their folder)."""
    if src.name in ("", ".", ".."):
        src = src.resolve()
    name = src.name[:-5] if src.name.endswith(".mcap") else src.name
    return src.with_name(f"{name}{suffix}.mcap")
