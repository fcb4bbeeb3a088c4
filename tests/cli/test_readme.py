"""Every `lfdfuse` command the README shows runs as a user types it, in order, in a fresh folder.

The folder is laid out as a fresh clone after `make demo`: `.venv` (the virtual environment running
these tests), `sample_logs/`, and `../shared` beside it when the shared folder exists (else the
commands reading it, and those reading what they wrote, are skipped). Each command runs in a new
`bash` after the README's own setup line (`source .venv/bin/activate`) with a PATH that holds no
virtual environment, so a README that forgets to say how to get the command fails here. Interactive
teleop is left to tests/sources/test_teleop.py.

Then every number the README quotes from a run (CLAIMS) is compared with what that run printed.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.conftest import ROOT, SHARED

README = ROOT / "README.md"


def _code_lines() -> list[str]:
    lines: list[str] = []
    inside = False
    for line in README.read_text().splitlines():
        if line.startswith("```"):
            inside = not inside
            continue
        if inside:
            lines.append(line)
    return lines


def readme_commands() -> list[str]:
    """The `lfdfuse …` lines of the README's code blocks, without comments and diagram arrows."""
    return [
        line.split("──►")[0].split("  #")[0].strip() for line in _code_lines() if line.startswith("lfdfuse ")
    ]


def setup_line() -> str:
    """The README's line that puts `lfdfuse` on the PATH after `make demo`."""
    found = [line.split("  #")[0].strip() for line in _code_lines() if line.startswith("source ")]
    assert found, "the README never says how to get the lfdfuse command after make demo"
    return found[0]


@dataclass(frozen=True)
class Claim:
    """A number the README quotes (``quote``, found verbatim) and where the run printed it.

    ``command`` starts the README command whose output holds the number; ``printed`` is a regex
    whose first group, in that output, must equal ``number`` (the number as the README writes it).
    """

    quote: str
    number: str
    command: str
    printed: str
    file: str | None = None  # the regex reads this output file of the command instead of its output


def _cell(method: str, column: int) -> str:
    """The regex of one cell of `lfdfuse evaluate`'s table: error (0), interval (1), median (2), turns (3)."""
    return rf"(?m)^ {method} +" + r"\S+ +" * column + r"([\d.]+)"


TURTLEBOT = "lfdfuse evaluate turtlebot.seg.mcap --holdout 0.3"
EVAL = "lfdfuse evaluate demo.seg.mcap --holdout 0.3"
OFFICE = "lfdfuse execute office.yaml --world office-room"
TB_IMPORT = "lfdfuse import ../shared/realdata/ros2/macfirst_floor_take_2.mcap"
NEATO = "lfdfuse import ../shared/realdata/ros1/neato-keyboard-middle.bag"
INTEL = "lfdfuse import ../shared/realdata/carmen/intel-corrected.log.gz"
_TB = {"fused": ("10.6", "25.5"), "nnls": ("9.5", "25.5"), "arbitration": ("42.7", "54.6")}
_TB |= {"straight": ("10.6", "38.2"), "previous": ("5.5", "12.7"), "oracle": ("8.0", "18.2")}

CLAIMS: tuple[Claim, ...] = (
    Claim("print `task NOT completed (2/3 goals)`", "2/3", OFFICE, r"task NOT completed \((\d+/\d+) goals\)"),
    Claim("with default weights on 7.7% of ticks", "7.7", OFFICE, r"default weights on ([\d.]+)% of ticks"),
    Claim(
        "0.0283 of ticks in the `tee` run above",
        "0.0283",
        "lfdfuse execute style.yaml --world tee",
        r'"reflex_fraction": ([\d.]+)',
        file="tee-run.json",
    ),
    *(
        Claim(f"| {row} | {s} | {c} recorded | {p} |", n, cmd, rx)
        for row, cmd, (s, c, p) in [
            ("TurtleBot 4, ROS 2 MCAP / rosbag2 / `.db3`", TB_IMPORT, ("357", "192", "920")),
            ("Neato, ROS 1", NEATO, ("185", "6", "278")),
        ]
        for n, rx in zip((s, c, p), (r"scans (\d+)", r"commands (\d+)", r"poses (\d+)"), strict=True)
    ),
    *(
        Claim("| CARMEN Intel | 910 | 909 derived | 910 |", n, INTEL, rx)
        for n, rx in (("910", r"scans (\d+)"), ("909", r"commands (\d+)"), ("910", r"poses (\d+)"))
    ),
    *(
        Claim(f"| {m} | {err} | {turns} |", n, TURTLEBOT, _cell(m, col))
        for m, (err, turns) in _TB.items()
        for n, col in ((err, 0), (turns, 3))
    ),
    Claim("on 76 held-out steps, most of them straight ahead", "76", TURTLEBOT, r"scored on (\d+) held-out"),
    Claim("where the person turned (21 steps)", "21", TURTLEBOT, r"turns ° \((\d+)\)"),
    Claim("fused 5.9°, oracle 4.6°, straight 5.6° overall", "5.9", EVAL, _cell("fused", 0)),
    Claim("fused 5.9°, oracle 4.6°, straight 5.6° overall", "4.6", EVAL, _cell("oracle", 0)),
    Claim("fused 5.9°, oracle 4.6°, straight 5.6° overall", "5.6", EVAL, _cell("straight", 0)),
    Claim("on the 118 turning steps", "118", EVAL, r"turns ° \((\d+)\)"),
    Claim("turning steps fused 11.9°, oracle 7.9°, straight 17.1°", "11.9", EVAL, _cell("fused", 3)),
    Claim("turning steps fused 11.9°, oracle 7.9°, straight 17.1°", "7.9", EVAL, _cell("oracle", 3)),
    Claim("turning steps fused 11.9°, oracle 7.9°, straight 17.1°", "17.1", EVAL, _cell("straight", 3)),
)


def test_the_readme_shows_commands() -> None:
    cmds = readme_commands()
    assert len(cmds) >= 20 and cmds[0] == "lfdfuse simulate"
    assert setup_line().startswith("source .venv/bin/activate")
    # the setup line comes before the first command a user would type
    text = README.read_text()
    assert text.index(setup_line()) < text.index("lfdfuse worlds")


def test_claims_are_in_the_readme() -> None:
    text = " ".join(README.read_text().split())
    for claim in CLAIMS:
        assert claim.quote in text, claim.quote
        assert claim.number in claim.quote, claim
        assert any(c.startswith(claim.command) for c in readme_commands()), claim.command


def _clean_env() -> dict[str, str]:
    """The environment of a new terminal: no virtual environment on the PATH."""
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONHOME")}
    venvs = {str(Path(sys.prefix) / "bin"), str(Path(sys.executable).parent)}
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if p not in venvs)
    # the venv may be an editable install of another checkout: run this checkout's code
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    env["COLUMNS"] = "100"
    return env


#: what a README command writes when it names no output (its ``--help`` default)
DEFAULT_OUT = {"simulate": "demo.mcap", "estimate": "fusion.yaml"}
#: the options that name a file a command writes
OUT_OPTIONS = ("-o", "--out", "--report", "--json")
#: live: teleop through a pty (tests/sources), drive and record against a robot (tests/drive, tests/record)
LIVE = ("teleop", "drive", "record")


def _outputs(args: list[str]) -> list[str]:
    return [args[i + 1] for i, a in enumerate(args[:-1]) if a in OUT_OPTIONS]


def _written(args: list[str]) -> list[str]:
    """The files a README command writes (its explicit outputs, else its default one)."""
    out = _outputs(args)
    if out:
        return out
    if args[0] == "segment":
        return [str(Path(args[1]).with_suffix(".seg.mcap").name)]
    return [DEFAULT_OUT[args[0]]] if args[0] in DEFAULT_OUT else []


def readme_chains() -> list[list[str]]:
    """The README's commands in independent chains, each in README order: a command joins the
    chain of every earlier command that wrote a file it reads or writes again. The chains run
    side by side (one test each); within one they run in order, as a user types them."""
    cmds = readme_commands()
    parent = list(range(len(cmds)))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    writer: dict[str, int] = {}
    for i, cmd in enumerate(cmds):
        args = shlex.split(cmd)[1:]
        names = {Path(a).name for a in args[1:]} | set(_written(args))
        for name in names:
            if name in writer:
                parent[root(i)] = root(writer[name])
        for name in _written(args):
            writer[name] = i
    chains: dict[int, list[str]] = {}
    for i, cmd in enumerate(cmds):
        chains.setdefault(root(i), []).append(cmd)
    return list(chains.values())


def _chain_id(chain: list[str]) -> str:
    args = shlex.split(chain[0])[1:]
    first = (_written(args) or args[1:] or args)[0].rstrip("/")
    return f"{Path(first).name.split('.')[0]}-{len(chain)}"


def test_the_chains_hold_every_command_once() -> None:
    chains = readme_chains()
    flat = [c for chain in chains for c in chain]
    assert sorted(flat) == sorted(readme_commands())
    assert len(flat) >= 20 and len(chains) >= 3
    # what a chain reads, no other chain writes
    for i, chain in enumerate(chains):
        reads = {Path(a).name for c in chain for a in shlex.split(c)[2:]}
        for j, other in enumerate(chains):
            if i != j:
                assert not reads & {w for c in other for w in _written(shlex.split(c)[1:])}
    # every quoted number is printed by a command of some chain
    assert all(any(c.startswith(claim.command) for c in flat) for claim in CLAIMS)


@pytest.mark.parametrize("chain", readme_chains(), ids=_chain_id)
def test_every_readme_command_works_as_written(tmp_path: Path, chain: list[str]) -> None:
    if not (Path(sys.prefix) / "bin" / "activate").exists():
        pytest.skip("the tests do not run in a virtual environment with bin/activate")
    clone = tmp_path / "lfdfuse"
    clone.mkdir()
    (clone / ".venv").symlink_to(Path(sys.prefix))
    shutil.copytree(ROOT / "sample_logs", clone / "sample_logs")
    has_shared = (SHARED / "realdata").is_dir()
    if has_shared:
        (tmp_path / "shared").symlink_to(SHARED.resolve())
    setup = setup_line()
    env = _clean_env()
    skipped: set[str] = set()
    printed: dict[str, str] = {}
    for cmd in chain:
        args = shlex.split(cmd)[1:]
        if any(Path(a).name.split(".")[0] in skipped for a in args[1:]):
            skipped.update(Path(o).name.split(".")[0] for o in _written(args))
            continue  # it reads what a skipped command would have written
        if args[0] in LIVE:  # a person or a robot at the other end: what it writes is not here
            skipped.update(Path(o).name.split(".")[0] for o in _written(args))
            continue
        if not has_shared and any("../shared" in a for a in args):
            skipped.update(Path(o).name.split(".")[0] for o in _outputs(args))
            continue
        res = subprocess.run(
            ["bash", "-c", f"{setup}\n{cmd}"],
            cwd=clone,
            env=env,
            capture_output=True,
            text=True,
            timeout=1800,
        )
        with (tmp_path / "printed.txt").open("a") as log:  # what a user saw, to read after a failure
            log.write(f"$ {cmd}\n{res.stdout}{res.stderr}[exit {res.returncode}]\n")
        assert res.returncode == 0, f"{cmd}\n{res.stdout}{res.stderr}"
        printed[cmd] = res.stdout + res.stderr
    if not printed:
        pytest.skip("nothing of this chain runs here: it is live, or reads ../shared, which is absent")
    wrong: list[str] = []  # every quoted number the run contradicts, not only the first
    for claim in CLAIMS:
        runs = [out for c, out in printed.items() if c.startswith(claim.command)]
        if not runs:
            continue  # another chain's, or skipped without ../shared
        text = (clone / claim.file).read_text() if claim.file else runs[0]
        m = re.search(claim.printed, text)
        assert m, f"{claim.command} printed nothing matching {claim.printed!r}:\n{runs[0]}"
        if m.group(1) != claim.number:
            wrong.append(f"README: {claim.quote!r}; {claim.command} printed {m.group(0)!r}")
    assert not wrong, "\n".join(wrong)


def test_the_readme_script_drives_without_a_collision(tmp_path: Path) -> None:
    """The scripted-teleop example, run as the README shows it, drives the default world cleanly."""
    from typer.testing import CliRunner

    from lfdfuse.cli.main import app

    text = README.read_text()
    block = re.search(r"\*\*Scripted\*\*.*?```yaml\n(.*?)```", text, re.S)
    assert block, "the README lost its scripted-teleop example"
    script = tmp_path / "drive.yaml"
    script.write_text(block.group(1))
    out = tmp_path / "d.mcap"
    res = CliRunner().invoke(app, ["teleop", "--input", "script", "--script", str(script), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert re.search(r"collisions\s+0\b", res.output), res.output
