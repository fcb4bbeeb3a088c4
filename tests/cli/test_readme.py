"""Every `lfdfuse` command the README shows runs as written, in order, in a fresh folder.

The pipeline diagram's commands run first (they make demo.mcap, demo.seg.mcap, fusion.yaml and
run.mcap with the defaults, as a newcomer would); `../shared` paths point at the shared folder
(those commands are skipped without it); interactive teleop is left to tests/sources/test_teleop.py.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
from pathlib import Path

from typer.testing import CliRunner

from lfdfuse.cli.main import app
from tests.conftest import ROOT, SHARED


def readme_commands() -> list[str]:
    commands: list[str] = []
    inside = False
    for line in (ROOT / "README.md").read_text().splitlines():
        if line.startswith("```"):
            inside = not inside
            continue
        if inside and line.startswith("lfdfuse "):
            cmd = line.split("──►")[0].split("  #")[0].strip()
            commands.append(cmd)
    return commands


def test_the_readme_shows_commands() -> None:
    cmds = readme_commands()
    assert len(cmds) >= 20 and cmds[0] == "lfdfuse simulate"


def test_every_readme_command_works_as_written(tmp_path: Path) -> None:
    shutil.copytree(ROOT / "sample_logs", tmp_path / "sample_logs")
    has_shared = (SHARED / "realdata").is_dir()
    if has_shared:
        (tmp_path.parent / "shared").mkdir(exist_ok=True)
    runner = CliRunner()
    ran = 0
    skipped: set[str] = set()
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        for cmd in readme_commands():
            args = shlex.split(cmd)[1:]
            if args[0] in ("teleop", "drive"):
                continue  # live: teleop through a pty (tests/sources), drive against a robot (tests/drive)
            if any(Path(a).name.split(".")[0] in skipped for a in args[1:]):
                continue  # it reads what a skipped command would have written
            if any("../shared" in a for a in args):
                if not has_shared:
                    skipped.update(Path(o).name.split(".")[0] for o in _outputs(args))
                    continue
                args = [re.sub(r"^\.\./shared", str(SHARED), a) for a in args]
            res = runner.invoke(app, args)
            assert res.exit_code == 0, f"{cmd}\n{res.output}"
            ran += 1
    finally:
        os.chdir(cwd)
    assert ran >= 20


def _outputs(args: list[str]) -> list[str]:
    return [args[i + 1] for i, a in enumerate(args[:-1]) if a in ("-o", "--out")]
