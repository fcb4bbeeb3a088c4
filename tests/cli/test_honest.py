"""Summaries say no more than the run showed (an empty demo is an error, thin rows are flagged,
a point fit has no ±), hints name the first missing step, and errors of one kind have one shape."""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from tests.conftest import ROOT, SHARED

runner = CliRunner()


@pytest.fixture()
def in_tmp(tmp_path: Path) -> Path:
    old = os.getcwd()
    os.chdir(tmp_path)
    yield tmp_path  # type: ignore[misc]
    os.chdir(old)


def _teach(script: str, name: str, *segment_options: str) -> Path:
    """A scripted teleop demo, segmented; returns the segmented log."""
    Path(f"{name}.drive.yaml").write_text(script)
    res = runner.invoke(
        app, ["teleop", "--input", "script", "--script", f"{name}.drive.yaml", "-o", f"{name}.mcap"]
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["segment", f"{name}.mcap", *segment_options])
    assert res.exit_code == 0, res.output
    return Path(f"{name}.seg.mcap")


def test_a_demo_without_an_informative_step_is_an_error(in_tmp: Path) -> None:
    # keys pressed, but only stop and reverse: no step carries a heading
    seg = _teach(
        "- {t: 0.0, key: k}\n- {t: 1.0, key: ','}\n- {t: 2.0, key: space}\n- {t: 3.0, end: true}\n", "still"
    )
    res = runner.invoke(app, ["estimate", str(seg), "-o", "still.yaml"])
    assert res.exit_code == 1, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "nothing to learn" in lines[0], res.stderr
    assert not Path("still.yaml").exists()


def test_a_row_from_a_handful_of_steps_is_flagged(in_tmp: Path) -> None:
    seg = _teach(
        "- {t: 0.0, key: i}\n- {t: 0.6, key: j}\n- {t: 1.2, key: k}\n- {t: 2.5, end: true}\n", "brief"
    )
    res = runner.invoke(app, ["estimate", str(seg), "-o", "brief.yaml"])
    assert res.exit_code == 0, res.output
    flagged = [ln for ln in res.stdout.splitlines() if "too few samples" in ln]
    assert len(flagged) == 1 and flagged[0].startswith("1 of 1 row"), res.stdout
    # inspect says the same of the written table
    res = runner.invoke(app, ["inspect", "brief.yaml"])
    assert res.exit_code == 0 and "too few samples" in res.stdout, res.output


@pytest.fixture(scope="module")
def short_demo(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("demo")
    res = runner.invoke(app, ["simulate", "--duration", "40", "-o", str(d / "d.mcap")])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["segment", str(d / "d.mcap")])
    assert res.exit_code == 0, res.output
    return d / "d.seg.mcap"


@pytest.mark.parametrize(
    ("method", "trials", "plusminus"), [("nnls", 1, False), ("nnls", 3, True), ("pf", 1, True)]
)
def test_a_table_says_what_made_it_and_claims_no_spread_it_lacks(
    short_demo: Path, tmp_path: Path, method: str, trials: int, plusminus: bool
) -> None:
    out = tmp_path / f"{method}.yaml"
    args = ["estimate", str(short_demo), "--method", method, "--trials", str(trials), "-o", str(out)]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    assert ("±" in res.stdout) is plusminus, res.stdout  # a point fit has no std; a bootstrap has one
    res = runner.invoke(app, ["inspect", str(out)])
    assert res.exit_code == 0, res.output
    made = [ln for ln in res.stdout.splitlines() if "made by:" in ln]
    assert len(made) == 1 and made[0].split("made by: ")[1].startswith(f"{method}, {trials} trial"), (
        res.stdout
    )
    assert f"from {short_demo.name}" in made[0]
    assert ("±" in res.stdout) is plusminus


def test_following_the_hints_reaches_the_goal(in_tmp: Path) -> None:
    """Each hint names the first missing step: doing what it says, and retrying, gets there."""
    bag = SHARED / "realdata" / "ros2" / "macfirst_floor_take_2.mcap"
    if not bag.exists():
        pytest.skip("../shared/realdata is not available")
    shutil.copy(bag, "bag.mcap")
    target = "bag.mcap"
    hints: list[str] = []
    for _ in range(4):
        res = runner.invoke(app, ["estimate", target, "-o", "f.yaml"])
        if res.exit_code == 0:
            break
        m = re.search(r"run `lfdfuse ([^`]+)` first", res.stderr)
        assert m, res.stderr
        hints.append(m.group(1).split()[0])
        hint = shlex.split(m.group(1))
        done = runner.invoke(app, hint)
        assert done.exit_code == 0, f"the hint {m.group(1)} fails:\n{done.output}"
        outs = [hint[i + 1] for i, a in enumerate(hint[:-1]) if a in ("-o", "--out")]
        target = outs[0] if outs else str(Path(hint[1]).with_suffix("")) + ".seg.mcap"
    assert hints == ["import", "segment"], hints
    assert Path("f.yaml").exists()


def test_evaluate_says_when_the_held_out_part_is_one_command(in_tmp: Path) -> None:
    # turning arcs, then straight ahead for the whole held-out part
    seg = _teach(
        "- {t: 0.0, key: u}\n- {t: 1.5, key: o}\n- {t: 3.0, key: i}\n- {t: 10.0, end: true}\n",
        "const",
        "--commands",
        "continuous",  # scored per tick: three presses are too few decisions for the discrete model
    )
    # the time split: its held-out last part is the one constant command
    res = runner.invoke(app, ["evaluate", str(seg), "--holdout", "0.3", "--json", "e.json"])
    assert res.exit_code == 0, res.output
    assert "nan" not in res.stdout.lower(), res.stdout  # no turn held out: no turn score, not nan
    assert "one constant command" in res.stdout and "no turn score" in res.stdout, res.stdout
    ev = json.loads(Path("e.json").read_text())  # strict JSON: NaN is not
    assert ev["held_out_headings"] == 1 and ev["turning_steps"] == 0
    assert all(m["turning_error_deg"] is None for m in ev["methods"].values())


# -- errors of one kind, one shape ------------------------------------------------------------


def _one_line_error(args: list[str]) -> str:
    res = runner.invoke(app, args)
    assert res.exit_code == 1, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    return lines[0]


def test_a_bad_script_yaml_is_one_line_naming_the_line(in_tmp: Path) -> None:
    Path("bad.yaml").write_text("- {t: 0.0, key: i\n- {t: 1\n")
    line = _one_line_error(["teleop", "--input", "script", "--script", "bad.yaml", "-o", "b.mcap"])
    assert "bad.yaml" in line and "line 2" in line, line
    assert not Path("b.mcap").exists()


@pytest.mark.parametrize("lag", ["-0.5", "1.5", "30"])
def test_a_lag_the_search_does_not_cover_is_refused(short_demo: Path, tmp_path: Path, lag: str) -> None:
    """A value outside what the option accepts: a usage error (exit 2) naming the range searched."""
    out = tmp_path / "x.seg.mcap"
    res = runner.invoke(app, ["segment", str(short_demo.with_name("d.mcap")), "--lag", lag, "-o", str(out)])
    text = " ".join(re.sub(r"[│╭╮╰╯─]", " ", res.output).split())
    assert res.exit_code == 2 and "--lag" in text and "0–1 s the lag search covers" in text, res.output
    assert not out.exists()


def test_a_closed_pipe_is_success(tmp_path: Path) -> None:
    """`lfdfuse … | head`: the reader stops reading; the command exits 0, silently."""
    exe = shutil.which(
        "lfdfuse", path=os.pathsep.join([str(Path(sys.executable).parent), os.environ["PATH"]])
    )
    assert exe
    for args in (["worlds"], ["inspect", str(ROOT / "sample_logs" / "three-goals.task.yaml")]):
        p = subprocess.Popen([exe, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path)
        assert p.stdout is not None and p.stderr is not None
        p.stdout.close()  # before the command writes: its first write meets a closed pipe
        err = p.stderr.read().decode()
        assert p.wait(timeout=60) == 0 and err == "", (args, err)
