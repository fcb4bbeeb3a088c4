"""`--help` reads cleanly at 80 columns (a pipe, many terminals) and at 120: prose wrapped by the
terminal and not twice, examples whole on one line, arguments as SRC, flags without a placeholder,
each default stated once."""

from __future__ import annotations

import inspect
import re
import shlex
from pathlib import Path

import pytest
import typer
import typer.rich_utils
from typer.testing import CliRunner

from lfdfuse.cli.main import app

runner = CliRunner()
COMMANDS = sorted(typer.main.get_group(app).commands)
WIDTHS = (80, 120)


def _help(args: list[str], width: int) -> str:
    # typer reads the width once, at import (TERMINAL_WIDTH); a terminal's COLUMNS ends there
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(typer.rich_utils, "MAX_WIDTH", width)
        res = runner.invoke(app, [*args, "--help"])
    assert res.exit_code == 0, res.output
    return res.stdout


def _examples(name: str) -> list[str]:
    cmd = typer.main.get_group(app).commands[name]
    doc = inspect.getdoc(cmd.callback) or ""  # as written, before it became help text
    return [
        ln.split(": ", 1)[-1].strip() for ln in doc.splitlines() if "lfdfuse " in ln.split(": ", 1)[-1][:10]
    ]


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("name", COMMANDS)
def test_help_reads_cleanly(name: str, width: int) -> None:
    out = _help([name], width)
    lines = out.splitlines()
    assert all(len(ln) <= width for ln in lines), f"{name}: a line wider than {width}"
    assert "<bool>" not in out, f"{name}: a flag shown with a <bool> placeholder"
    assert "<list[" not in out and "......" not in out, f"{name}: a list shown as a Python type"
    assert not re.search(r"\w…", out), f"{name} at {width}: a word cut short by an ellipsis"
    # a choice or a range is read whole: never wrapped inside a word or a number
    cmd = typer.main.get_group(app).commands[name]
    for p in cmd.params:
        desc = getattr(p, "type_descriptor", None)
        for choice in (desc.choices or ()) if desc is not None and desc.is_choice else ():
            word = str(getattr(choice, "value", choice))
            assert re.search(rf"[<| ]{re.escape(word)}[ |>]", out), f"{name} at {width}: choice {word} cut"
        for bound in (getattr(p, "min", None), getattr(p, "max", None)):
            if isinstance(bound, int | float) and not isinstance(bound, bool) and abs(bound) < 1e6:
                assert re.search(rf"(?<![\d.]){re.escape(str(bound))}(?![\d.])", out), (
                    f"{name} at {width}: {p.name}'s bound {bound} cut"
                )
    assert not re.search(r"\{[a-z_]+\}", out), f"{name}: an argument shown as {{name}}"
    # every example on one line, whole (a user copies it)
    examples = _examples(name)
    assert examples, f"{name} --help has no example"
    for ex in examples:
        assert any(ln.strip() == ex for ln in lines), f"{name} at {width}: example cut: {ex}"
    # the prose is wrapped once, by the terminal: a line ends early only where its paragraph does
    prose = lines[: next(i for i, ln in enumerate(lines) if ln.startswith("╭"))]
    for a, b in zip(prose, prose[1:], strict=False):
        if not a.strip() or not b.strip() or b.startswith("   ") or a.strip().endswith(":"):
            continue
        first = b.split()[0]
        assert len(a.strip()) + 1 + len(first) > width - 2, f"{name} at {width}: wrapped early:\n{a}\n{b}"


@pytest.mark.parametrize("name", COMMANDS)
def test_each_default_is_stated_once(name: str) -> None:
    cmd = typer.main.get_group(app).commands[name]
    for p in cmd.params:
        shown = getattr(p, "show_default", True) is not False and p.default not in (None, False, ())
        if shown and p.help:
            assert not re.search(r"\bdefault[:s]? ", p.help, re.I), (
                f"{name} {p.name}: default said twice: {p.help}"
            )


def test_the_root_help_lists_every_command() -> None:
    for width in WIDTHS:
        out = _help([], width)
        assert "<bool>" not in out, f"lfdfuse --help at {width}: a flag shown with a <bool> placeholder"
        for name in COMMANDS:
            assert re.search(rf"│ {name}\s", out), f"{name} missing from lfdfuse --help at {width}"


@pytest.mark.parametrize("name", COMMANDS)
def test_every_example_is_a_valid_command_line(name: str, tmp_path: Path) -> None:
    """Each example, as written, names real options with values they accept (click parses it,
    with every file it names present): a copied example never fails on its own usage."""
    group = typer.main.get_group(app)
    cmd = group.commands[name]
    for ex in _examples(name):
        args = shlex.split(ex)[2:]
        with pytest.MonkeyPatch.context() as mp:
            mp.chdir(tmp_path)
            for a in args:
                if re.search(r"\.(mcap|yaml|bag|gz|db3|json|png|svg)$", a) and "/" not in a:
                    (tmp_path / a).touch()
            try:
                cmd.make_context(name, list(args))
            except typer.TyperException as exc:  # typer's click: a usage error of any kind
                pytest.fail(f"lfdfuse {name} --help example does not parse: {ex}\n{exc}")
