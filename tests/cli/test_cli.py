"""The CLI: help everywhere, one-line errors with exit 1, nothing left behind, the real command."""

from __future__ import annotations

import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import typer
import typer.rich_utils
from typer.testing import CliRunner

from lfdfuse.cli.app import COMMANDS
from lfdfuse.cli.main import app
from tests.conftest import ROOT

runner = CliRunner()


def _commands() -> list[str]:
    group = typer.main.get_group(app)
    return sorted(group.commands)


def test_every_command_has_help_with_an_example() -> None:
    for name in _commands():
        res = runner.invoke(app, [name, "--help"])
        assert res.exit_code == 0, name
        assert "Example" in res.output, f"{name} --help has no example"


_IMPORTED = """
import sys
import typer.rich_utils
from typer.testing import CliRunner
from lfdfuse.cli.main import app
typer.rich_utils.MAX_WIDTH = 100
res = CliRunner().invoke(app, sys.argv[1:])
assert res.exit_code == 0, res.output
print(res.output)
print(sorted(m for m in sys.modules if m.startswith("lfdfuse.")))
"""


def _run_reporting_imports(*args: str) -> tuple[str, list[str]]:
    res = subprocess.run(
        [sys.executable, "-c", _IMPORTED, *args], capture_output=True, text=True, timeout=600, cwd=ROOT
    )
    assert res.returncode == 0, res.stderr
    *out, modules = res.stdout.rstrip("\n").split("\n")
    return "\n".join(out), list(ast.literal_eval(modules))


def test_help_lists_every_command_without_importing_any() -> None:
    """`lfdfuse --help` reads each command's help from its source: no command module is imported
    (starting one command costs only its own imports), and the list is the one the commands give."""
    out, modules = _run_reporting_imports("--help")
    assert [m for m in modules if m.startswith("lfdfuse.cli.") and m.split(".")[2] in COMMANDS.values()] == []
    assert not any(m.startswith(("lfdfuse.sim", "lfdfuse.estimate", "lfdfuse.world")) for m in modules), (
        modules
    )
    # the same list as with every command imported and built (in-process, all loaded by now)
    group = typer.main.get_group(app)
    built = {name: group.commands[name] for name in COMMANDS}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(typer.rich_utils, "MAX_WIDTH", 100)
        full = runner.invoke(app, ["--help"])
    assert full.exit_code == 0 and out.strip() == full.output.strip()
    for name, cmd in built.items():
        assert name in out and cmd.help and cmd.help.split("\n\n")[0].split()[0] in out


def test_one_command_imports_only_its_own_module(tmp_path: Path) -> None:
    _, modules = _run_reporting_imports("worlds")
    commands = {m.split(".")[2] for m in modules if m.startswith("lfdfuse.cli.")} & set(COMMANDS.values())
    assert commands == {"worlds"}


def test_worlds_lists_builtins() -> None:
    res = runner.invoke(app, ["worlds"])
    assert res.exit_code == 0
    for name in ("corridor", "tee", "building", "obstacles"):
        assert name in res.output


def _error(args: list[str], cwd: Path) -> str:
    before = set(os.listdir(cwd))
    res = runner.invoke(app, args)
    assert res.exit_code == 1, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    assert "Traceback" not in res.output
    assert set(os.listdir(cwd)) == before, "a failed command left a file behind"
    return lines[0]


@pytest.fixture()
def in_tmp(tmp_path: Path) -> Path:
    old = os.getcwd()
    os.chdir(tmp_path)
    yield tmp_path  # type: ignore[misc]
    os.chdir(old)


def test_simulate_bad_input(in_tmp: Path) -> None:
    assert "building, corridor, obstacles, office-room, ring-spur, ring-spur-large, tee" in _error(
        ["simulate", "--world", "mars", "-o", "x.mcap"], in_tmp
    )
    (in_tmp / "bad.yaml").write_text("walls: [[[0, 0], [1, 1]]\nstart: [")
    assert "malformed YAML" in _error(["simulate", "--world", "bad.yaml", "-o", "x.mcap"], in_tmp)
    (in_tmp / "key.yaml").write_text(
        "walls: [[[0, 0], [9, 0], [9, 9], [0, 0]]]\nstart: [5, 2, 0]\nfloor: 1\n"
    )
    assert "unknown key 'floor'" in _error(["simulate", "--world", "key.yaml", "-o", "x.mcap"], in_tmp)
    assert "start pose" in _error(["simulate", "--start", "0,0,0", "-o", "x.mcap"], in_tmp)
    assert "cannot write" in _error(["simulate", "--duration", "2", "-o", "no/such/dir/x.mcap"], in_tmp)
    assert "unknown teacher style" in _error(["simulate", "--teacher", "zigzag", "-o", "x.mcap"], in_tmp)
    (in_tmp / "task.yaml").write_text("task:\n  - {target: purple, style: keep-left}\n")
    assert "no target 'purple'" in _error(["simulate", "--teacher", "task.yaml", "-o", "x.mcap"], in_tmp)


@pytest.mark.parametrize("target", ["missing/x.mcap", "afile/x.mcap"])
def test_unwritable_output_leaves_nothing(in_tmp: Path, target: str) -> None:
    """An output in a missing folder, or under a path that is a file (unwritable even for root)."""
    (in_tmp / "afile").write_text("not a folder")
    before = sorted(p.name for p in in_tmp.rglob("*"))
    assert "cannot write" in _error(["simulate", "--duration", "2", "-o", target], in_tmp)
    assert sorted(p.name for p in in_tmp.rglob("*")) == before


def test_inspect_bad_input(in_tmp: Path) -> None:
    assert "no such file" in _error(["inspect", "nothing.mcap"], in_tmp)
    (in_tmp / "junk.mcap").write_bytes(b"not an mcap file at all")
    assert "not a readable MCAP" in _error(["inspect", "junk.mcap"], in_tmp)


def test_simulate_then_inspect(in_tmp: Path) -> None:
    res = runner.invoke(
        app,
        ["simulate", "--world", "corridor", "--teacher", "keep-right", "--duration", "10", "-o", "d.mcap"],
    )
    assert res.exit_code == 0, res.output
    assert "collisions" in res.output and (in_tmp / "d.mcap").exists()
    res = runner.invoke(app, ["inspect", "d.mcap"])
    assert res.exit_code == 0
    assert "/scan" in res.output and "foxglove.LaserScan" in res.output and "101" in res.output


def test_the_installed_command_runs(tmp_path: Path) -> None:
    exe = shutil.which("lfdfuse", path=str(Path(sys.executable).parent)) or shutil.which("lfdfuse")
    assert exe, "the lfdfuse console script is not installed"
    out = tmp_path / "x.mcap"
    res = subprocess.run(
        [exe, "simulate", "--world", "tee", "--duration", "5", "-o", str(out)], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    assert out.exists()
    bad = subprocess.run([exe, "simulate", "--world", "nowhere"], capture_output=True, text=True)
    assert bad.returncode == 1 and bad.stderr.startswith("error: unknown world 'nowhere'")
    usage = subprocess.run([exe, "simulate", "--duration", "abc"], capture_output=True, text=True)
    assert usage.returncode == 2


def test_the_installed_command_runs_the_whole_pipeline(tmp_path: Path) -> None:
    exe = shutil.which("lfdfuse", path=str(Path(sys.executable).parent)) or shutil.which("lfdfuse")
    assert exe
    steps = [
        ["simulate", "--world", "corridor", "--teacher", "keep-right", "--duration", "60", "-o", "d.mcap"],
        [
            "segment",
            "d.mcap",
            "--behaviors",
            "avoid,wander_left,wander_right,wall_attract_left,wall_attract_right",
        ],
        ["estimate", "d.seg.mcap", "-o", "f.yaml", "--particles", "300"],
        [
            "execute",
            "f.yaml",
            "--world",
            "corridor",
            "--max-time",
            "40",
            "-o",
            "r.mcap",
            "--report",
            "r.json",
        ],
    ]
    for args in steps:
        res = subprocess.run([exe, *args], capture_output=True, text=True, cwd=tmp_path)
        assert res.returncode == 0, (args, res.stderr)
    import json

    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["steps"][0]["style"] == "right" and rep["collisions"] == 0
