"""The typer application every command registers on, and what commands share."""

from __future__ import annotations

import ast
import importlib
import inspect
import re
from collections.abc import Iterator, MutableMapping
from pathlib import Path
from typing import Any

import typer
import typer.main
from typer.core import TyperArgument, TyperCommand, TyperGroup

from lfdfuse import __version__
from lfdfuse.cli.common import MAX_SEED


def _tidy(params: list[Any]) -> list[Any]:  # typer's parameter classes are a vendored click: Any
    """Parameters as their help should show them at 80 columns: a flag with nothing after its
    name, an argument by its NAME (with ``...`` when it takes several), a repeatable option by
    the kind of one value, a choice as
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
        elif getattr(p, "multiple", False) and p.metavar is None:  # repeated: one value each time
            p.metavar = "<path>" if desc is not None and "Path" in str(desc.annotation) else "<value>"
        elif desc is not None and desc.is_choice and p.metavar is None:
            p.metavar = "<" + " | ".join(str(getattr(c, "value", c)) for c in desc.choices or ()) + ">"
        if getattr(p, "max", None) == MAX_SEED:
            p._get_number_range_help_str = lambda low=p.min: f"x>={low}"
    return params


#: every command, in the order ``--help`` lists them, and the module of this package that holds it;
#: a module is imported only when its command runs (or shows its own help), so starting one
#: command never pays for the others' imports
COMMANDS = {
    "drive": "drive",
    "estimate": "estimate",
    "evaluate": "evaluate",
    "execute": "execute",
    "import": "import_cmd",
    "inspect": "inspect",
    "plot": "plot",
    "record": "record",
    "report": "report",
    "segment": "segment",
    "simulate": "simulate",
    "teleop": "teleop",
    "worlds": "worlds",
}


def _summary(name: str) -> str:
    """A command's help read from its module's source, without importing the module: the
    docstring of the function registered as ``name`` (what :func:`finish` makes its help)."""
    path = Path(__file__).with_name(f"{COMMANDS[name]}.py")
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if not isinstance(node, ast.FunctionDef):
            continue
        for dec in node.decorator_list:
            call = dec if isinstance(dec, ast.Call) else None
            target = call.func if call is not None else dec
            if not (isinstance(target, ast.Attribute) and target.attr == "command"):
                continue
            given = call.args[0] if call is not None and call.args else None
            registered = given.value if isinstance(given, ast.Constant) else node.name.replace("_", "-")
            if registered == name:
                return help_text(ast.get_docstring(node, clean=False) or "")
    raise LookupError(f"lfdfuse.cli.{COMMANDS[name]} registers no command {name!r}")


class _Commands(MutableMapping[str, Any]):
    """The root's commands by name: every name in :data:`COMMANDS` is listed from the start; a
    command is built (its module imported and registered on :data:`app`) when first looked up."""

    def __init__(self, built: MutableMapping[str, Any]) -> None:
        self._built = dict(built)
        # a command module imported before the root was built (a test, a library user) registered
        # its command as typer would: build it again as every lazily imported one is built
        finish(app)
        for info in app.registered_commands:
            name = _registered_name(info)
            if name in self._built and not isinstance(self._built[name], Command):
                self._built[name] = self._build(info)

    def __getitem__(self, name: str) -> Any:
        if name not in self._built:
            if name not in COMMANDS:
                raise KeyError(name)
            importlib.import_module(f"lfdfuse.cli.{COMMANDS[name]}")
            finish(app)
            info = next(i for i in app.registered_commands if _registered_name(i) == name)
            self._built[name] = self._build(info)
        return self._built[name]

    @staticmethod
    def _build(info: Any) -> Any:
        return typer.main.get_command_from_info(
            info, pretty_exceptions_short=app.pretty_exceptions_short, rich_markup_mode=app.rich_markup_mode
        )

    def __setitem__(self, name: str, cmd: Any) -> None:
        self._built[name] = cmd

    def __delitem__(self, name: str) -> None:
        del self._built[name]

    def __iter__(self) -> Iterator[str]:
        yield from COMMANDS
        yield from (n for n in self._built if n not in COMMANDS)

    def __len__(self) -> int:
        return len(COMMANDS) + sum(n not in COMMANDS for n in self._built)

    def __contains__(self, name: object) -> bool:
        return name in COMMANDS or name in self._built

    def listed(self, name: str) -> Any:
        """The command as the root's help lists it: the built one, or its name and help alone."""
        if name in self._built:
            return self._built[name]
        return TyperCommand(name=name, help=_summary(name), rich_markup_mode=app.rich_markup_mode)


def _registered_name(info: Any) -> str:
    return str(info.name or info.callback.__name__.replace("_", "-"))


class Group(TyperGroup):
    """The root command, its options shown as the commands' are (:func:`_tidy`), its commands
    imported only when one is run (``lfdfuse --help`` lists them all from their sources)."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.commands = _Commands(self.commands)
        self._listing = False

    def get_params(self, ctx: Any) -> list[Any]:
        return _tidy(super().get_params(ctx))

    def list_commands(self, ctx: Any) -> list[str]:
        return list(self.commands)  # the names alone: typer's own reads every command

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        if self._listing and isinstance(self.commands, _Commands) and cmd_name in COMMANDS:
            return self.commands.listed(cmd_name)
        return super().get_command(ctx, cmd_name)

    def format_help(self, ctx: Any, formatter: Any) -> None:
        self._listing = True
        try:
            super().format_help(ctx, formatter)
        finally:
            self._listing = False


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
