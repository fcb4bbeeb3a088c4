"""A wrong command line gets one line and the right exit code, and leaves nothing behind."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.log.reader import MCAP_MAGIC
from tests.hostile.base import TABLE_YAML

runner = CliRunner()


def _in(folder: Path, args: list[str]) -> tuple[int, str]:
    old = os.getcwd()
    os.chdir(folder)
    try:
        res = runner.invoke(app, args)
    finally:
        os.chdir(old)
    return res.exit_code, res.output


@pytest.mark.parametrize("arg", [".", "..", "sub"])
def test_segment_of_a_folder_is_one_line(tmp_path: Path, arg: str) -> None:
    (tmp_path / "sub").mkdir()
    code, out = _in(tmp_path / "sub" if arg == ".." else tmp_path, ["segment", arg])
    assert code == 1, out
    assert "is a folder" in out and "Traceback" not in out
    assert len(out.strip().splitlines()) == 1


def test_report_refuses_a_negative_seed_before_writing(tmp_path: Path) -> None:
    code, out = _in(tmp_path, ["report", "--seed", "-3", "-o", "rep", "--quick"])
    assert code == 2 and "--seed" in out
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("option", "value"), [("--v-max", "-1"), ("--omega-max", "0"), ("--v-max", "nan")])
def test_import_refuses_a_limit_it_would_drop(tmp_path: Path, option: str, value: str) -> None:
    (tmp_path / "x.bag").write_bytes(b"#ROSBAG V2.0\n")
    code, out = _in(tmp_path, ["import", "x.bag", option, value, "-o", "x.mcap"])
    assert code == 2 and option in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.bag"]


def test_execute_refuses_a_log_it_would_not_write(tmp_path: Path) -> None:
    code, out = _in(tmp_path, ["execute", "t.yaml", "--starts", "2", "-o", "r.mcap"])
    assert code == 2 and "--starts" in out
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("after", [b"", b"\x01" + (13).to_bytes(8, "little") + bytes(13)])
def test_zeros_after_the_magic_are_refused_at_once(tmp_path: Path, after: bytes) -> None:
    """A file of zeros behind the magic bytes (and behind a header) is refused on its first record."""
    bad = tmp_path / "z.mcap"
    bad.write_bytes(MCAP_MAGIC + after + bytes(8 * 2**20) + MCAP_MAGIC)
    code, out = _in(tmp_path, ["segment", "z.mcap"])
    assert code == 1 and "not a readable MCAP file" in out, out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["z.mcap"]


@pytest.mark.parametrize(
    "args",
    [
        ["segment", "x.mcap", "--lag", "5"],
        ["segment", "x.mcap", "--lag", "abc"],
        ["simulate", "-o", "s.mcap", "--start", "1,2"],
        ["execute", "t.yaml", "--start", "1,2,nan"],
        ["execute", "t.yaml", "--starts", "0"],
        ["teleop", "--start", "x"],
    ],
)
def test_a_value_the_option_does_not_accept_is_a_usage_error(tmp_path: Path, args: list[str]) -> None:
    """Exit 2 (as click's own ranges), the option named, before any input is read or output made."""
    code, out = _in(tmp_path, args)
    assert code == 2, out
    assert args[-2] in out
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("keep", [0.1, 0.5, 0.99])
def test_a_cut_mcap_says_it_is_truncated_and_where(tmp_path: Path, keep: float) -> None:
    whole = (Path(__file__).resolve().parents[2] / "sample_logs" / "keep-left-building.mcap").read_bytes()
    cut = whole[: int(keep * len(whole))]
    (tmp_path / "c.mcap").write_bytes(cut)
    for cmd in (["inspect", "c.mcap"], ["segment", "c.mcap"]):
        code, out = _in(tmp_path, cmd)
        assert code == 1 and f"truncated MCAP file: it ends at byte {len(cut)}" in out, out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.mcap"]


@pytest.mark.parametrize("cmd", [["inspect", "."], ["inspect", "sub"], ["plot", "sub", "-o", "p.png"]])
def test_a_folder_that_is_not_a_bag_is_named_as_a_folder(tmp_path: Path, cmd: list[str]) -> None:
    (tmp_path / "sub").mkdir()
    code, out = _in(tmp_path, cmd)
    assert code == 1 and "is a folder" in out and "import" not in out, out


def test_a_segmented_demo_is_not_segmented_into_a_seg_seg_file(tmp_path: Path) -> None:
    (tmp_path / "d.seg.mcap").write_bytes(b"")
    code, out = _in(tmp_path, ["segment", "d.seg.mcap"])
    assert code == 1 and "segmented already" in out and "-o" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.seg.mcap"]


def test_a_goal_target_that_is_null_is_refused(tmp_path: Path) -> None:
    table = TABLE_YAML.replace("goal: null", "goal: {target: null}", 1)
    assert table != TABLE_YAML
    (tmp_path / "t.yaml").write_text(table)
    code, out = _in(tmp_path, ["execute", "t.yaml", "--world", "tee", "--max-time", "1"])
    assert code == 1 and "goal.target must be a target's name" in out, out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.yaml"]


def test_a_goal_the_world_lacks_is_said_at_the_start(tmp_path: Path) -> None:
    table = TABLE_YAML.replace("goal: null", "goal: {target: red}", 1)
    (tmp_path / "t.yaml").write_text(table)
    code, out = _in(tmp_path, ["execute", "t.yaml", "--world", "corridor", "--max-time", "1"])
    assert code == 0, out
    first = out.strip().splitlines()[0]
    assert first.startswith("warning: world 'corridor' has no target red"), out


def test_segment_durations_add_up_to_the_demo(tmp_path: Path) -> None:
    """Goal segments' seconds come from the stamps: they add up to the demo's span, not steps × 0.1 s."""
    task = Path(__file__).resolve().parents[2] / "sample_logs" / "three-goals.task.yaml"
    code, out = _in(tmp_path, ["simulate", "--teacher", str(task), "--duration", "60", "-o", "d.mcap"])
    assert code == 0, out
    code, out = _in(tmp_path, ["segment", "d.mcap"])
    assert code == 0, out
    secs = [float(m) for m in re.findall(r"segment \d+ → [^:]+: ([0-9.]+) s", out)]
    assert len(secs) >= 2, out  # red is reached within the minute
    assert abs(sum(secs) - 60.0) <= 0.05 * len(secs), (secs, out)
