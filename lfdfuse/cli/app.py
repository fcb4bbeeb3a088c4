"""The typer application every command registers on, and what commands share."""

from __future__ import annotations

import inspect
import re
from pathlib import Path
from typing import Any

import typer
from typer.core import TyperArgument, TyperCommand, TyperGroup

from lfdfuse import __version__
from lfdfuse.cli.common import MAX_SEED


def _tidy(params: list[Any]) -> list[Any]:  # typer's parameter classes are a vendored click: Any
    """Parameters as their help should show them at 80 columns: a flag with nothing after its
    name, an argument by its NAME (with ``...`` when it takes several), a choice as
    ``<a | b | c>`` (so a narrow column wraps between choices, never inside one), and a seed's
    range without its 19-digit top."""
    for p in params:
        desc = getattr(p, "type_descriptor", None)
        if getattr(p, "is_flag", False):
            p.metavar = ""  # a flag takes no value: nothing to show after its name
        elif isinstance(p, TyperArgument):
            arg: Any = p  # narrowed to typer's class, whose display method is replaced below
            if arg.metavar is None and arg.name:
                arg.metavar = arg.name.upper()
            if arg.nargs != 1:
                arg.metavar = (arg.metavar or "").removesuffix("...") + "..."
                kind = "path" if "Path" in arg.bare_type() else "value"
                arg.display_type_rich = lambda ctx, kind=kind: f"<{kind}>..."
        elif desc is not None and desc.is_choice and p.metavar is None:
            p.metavar = "<" + " | ".join(str(getattr(c, "value", c)) for c in desc.choices or ()) + ">"
        if getattr(p, "max", None) == MAX_SEED:
            p._get_number_range_help_str = lambda low=p.min: f"x>={low}"
    return params


class Group(TyperGroup):
    """The root command, its options shown as the commands' are (:func:`_tidy`)."""

    def get_params(self, ctx: Any) -> list[Any]:
        return _tidy(super().get_params(ctx))


app = typer.Typer(
    name="lfdfuse",
    cls=Group,
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
    """A command whose help shows its parameters as :func:`_tidy` says."""

    # typer's context and parameter classes are its own (a vendored click): typed as Any here
    def get_params(self, ctx: Any) -> list[Any]:
        return _tidy(super().get_params(ctx))

    def collect_usage_pieces(self, ctx: Any) -> list[str]:
        pieces = [self.options_metavar] if self.options_metavar else []
        for p in self.get_params(ctx):
            if isinstance(p, TyperArgument):
                name = p.metavar or p.name or ""
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
