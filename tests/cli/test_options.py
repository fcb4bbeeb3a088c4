"""Options are typed: typer checks ranges and choices; out of range or a bad choice is
a usage error (exit 2, click's message) before any work, the same in every command."""

from __future__ import annotations

import typing
from enum import Enum
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from lfdfuse.cli.import_cmd import CmdSource, Driver, Format
from lfdfuse.cli.main import app
from lfdfuse.sources.importers import FORMATS
from lfdfuse.sources.importers.convert import CmdFrom, ImportOptions

runner = CliRunner()

#: numbers whose range only the library can judge (an open interval, a lag against the log,
#: a robot's limit that must be positive): they stay one ``error:`` line, exit 1
LIBRARY_RANGES = {("evaluate", "holdout"), ("segment", "lag"), ("import", "v_max"), ("import", "omega_max")}


def _options() -> list[tuple[str, typing.Any]]:
    group = typer.main.get_group(app)
    return [(name, p) for name, cmd in sorted(group.commands.items()) for p in cmd.params]


def test_every_number_has_its_range_declared() -> None:
    for command, p in _options():
        kind = p.type_descriptor.annotation
        if kind not in (int, float) or (command, p.name) in LIBRARY_RANGES:
            continue
        assert p.min is not None or p.max is not None, f"{command} --{p.name}: a number without a range"


def test_every_choice_is_an_enum_typer_offers() -> None:
    choices = [(c, p) for c, p in _options() if isinstance(p.type_descriptor.annotation, type)]
    enums = [(c, p) for c, p in choices if issubclass(p.type_descriptor.annotation, Enum)]
    assert {(c, p.name) for c, p in enums} >= {
        ("import", "fmt"),
        ("import", "cmd_from"),
        ("import", "teacher"),
        ("teleop", "input_"),
        ("plot", "whiskers"),
    }
    for command, p in enums:
        res = runner.invoke(app, [command, "--help"], env={"COLUMNS": "200"})
        assert res.exit_code == 0
        for member in p.type_descriptor.annotation:
            assert member.value in res.output, f"{command} --help does not offer {member.value}"


def test_the_import_choices_are_the_library_s_own() -> None:
    assert [f.value for f in Format] == list(FORMATS)
    assert [c.value for c in CmdSource] == list(typing.get_args(CmdFrom))
    teacher = typing.get_type_hints(ImportOptions)["teacher"]
    assert [d.value for d in Driver] == list(typing.get_args(teacher))


def _usage(args: list[str]) -> str:
    res = runner.invoke(app, args)
    assert res.exit_code == 2, (args, res.output)
    assert "Usage" in res.output and "Traceback" not in res.output
    return res.output


@pytest.mark.parametrize(
    "args",
    [
        ["simulate", "--duration", "0"],
        ["simulate", "--duration", "nan"],
        ["simulate", "--duration", "1e9"],
        ["simulate", "--seed", "-1"],
        ["simulate", "--seed", str(2**63)],
        ["simulate", "--sensor-noise", "2"],
        ["simulate", "--heading-noise", "-1"],
        ["simulate", "--heading-noise", "inf"],
        ["execute", "t.yaml", "--max-time", "-1"],
        ["execute", "t.yaml", "--sensor-noise", "nan"],
        ["execute", "t.yaml", "--seed", "-5"],
        ["teleop", "--port", "65536"],
        ["teleop", "--timeout", "0"],
        ["teleop", "--timeout", "inf"],
        ["teleop", "--duration", "0"],
        ["evaluate", "s.mcap", "--seed", "-1"],
        ["import", "x.bag", "--format", "rosbag"],
        ["import", "x.bag", "--cmd-from", "joystick"],
        ["import", "x.bag", "--teacher", "robot"],
        ["teleop", "--input", "gamepad"],
        ["plot", "t.yaml", "-o", "x.png", "--whiskers", "nope"],
    ],
)
def test_out_of_range_or_a_bad_choice_is_a_usage_error(tmp_path: Path, args: list[str]) -> None:
    """Before any work: nothing written, no file read (the inputs named here do not exist)."""
    out = _usage([*args, "-o", str(tmp_path / "o.mcap")] if args[0] in ("simulate", "teleop") else args)
    assert "Invalid value" in out
    assert list(tmp_path.iterdir()) == []


def test_the_edges_of_a_range_are_in_it(tmp_path: Path) -> None:
    res = runner.invoke(
        app,
        ["simulate", "--world", "tee", "--duration", "0.1", "--seed", str(2**63 - 1), "--sensor-noise", "1"]
        + ["--heading-noise", "180", "-o", str(tmp_path / "d.mcap")],
    )
    assert res.exit_code == 0, res.output
