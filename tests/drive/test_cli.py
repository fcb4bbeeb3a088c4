"""``lfdfuse drive`` on the command line: one-line errors, exit codes, nothing left behind."""

from __future__ import annotations

import socket
from pathlib import Path

import yaml
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.world.model import load_world
from tests.support.bridge_sim import BridgeSim

runner = CliRunner()


def _one_error_line(output: str, text: str) -> None:
    lines = [ln for ln in output.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1 and text in lines[0], output
    assert "Traceback" not in output


def test_bad_options_are_one_line_errors(keep_left: Path, tmp_path: Path) -> None:
    out = tmp_path / "live.mcap"
    res = runner.invoke(app, ["drive", str(keep_left), "--connect", "http://robot:8765", "-o", str(out)])
    assert res.exit_code == 1
    _one_error_line(res.output, "--connect must be a ws://HOST:PORT URL")
    for opt, value in (
        ("--max-speed", "-0.2"),
        ("--max-speed", "nan"),
        ("--max-turn", "0"),
        ("--duration", "1e9"),
    ):
        res = runner.invoke(app, ["drive", str(keep_left), "--connect", "ws://x:1", opt, value])
        assert res.exit_code == 2 and opt in res.output  # out of range: bad usage
    res = runner.invoke(app, ["drive", str(keep_left)])
    assert res.exit_code == 2  # --connect is required: bad usage
    res = runner.invoke(app, ["drive", str(tmp_path / "nope.yaml"), "--connect", "ws://x:1"])
    assert res.exit_code == 1 and "error:" in res.output
    assert list(tmp_path.iterdir()) == []


def test_nobody_listening_is_a_clear_error(keep_left: Path, tmp_path: Path) -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "live.mcap"
    res = runner.invoke(app, ["drive", str(keep_left), "--connect", f"ws://127.0.0.1:{port}", "-o", str(out)])
    assert res.exit_code == 1
    _one_error_line(res.output, f"cannot connect to ws://127.0.0.1:{port}")
    assert list(tmp_path.iterdir()) == []


def test_nobody_listening_for_a_whole_duration_is_the_same_error(keep_left: Path, tmp_path: Path) -> None:
    """A ``--duration`` that ends before any connection opened is no run: exit 1, no file."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "d.mcap"
    args = ["drive", str(keep_left), "--connect", f"ws://127.0.0.1:{port}", "--duration", "2", "-o", str(out)]
    res = runner.invoke(app, args)
    assert res.exit_code == 1
    _one_error_line(res.output, f"cannot connect to ws://127.0.0.1:{port}")
    assert "ticks" not in res.output and list(tmp_path.iterdir()) == []


def test_a_table_the_robot_cannot_run_is_refused(keep_left: Path, tmp_path: Path) -> None:
    """Every step leans on the camera's targets; a ROS 2 bridge streams no targets."""
    table = yaml.safe_load(keep_left.read_text())
    for step in table["network"]["steps"]:
        step.pop("default_weights", None)
        step["fusion"] = [{"bac": 3, "weights": {"attract_red": 0.9, "avoid": 0.1}, "samples": 50}]
    path = tmp_path / "needs-camera.yaml"
    path.write_text(yaml.safe_dump(table))
    out = tmp_path / "live.mcap"
    with BridgeSim(load_world("tee"), encoding="cdr", lockstep=False) as robot:
        res = runner.invoke(app, ["drive", str(path), "--connect", robot.url, "-o", str(out)])
    assert res.exit_code == 1
    _one_error_line(res.output, "every step of the table needs camera")
    assert "behaviours it has: avoid" in res.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["needs-camera.yaml"]


def test_a_server_without_the_scan_topic(keep_left: Path, tmp_path: Path) -> None:
    with BridgeSim(load_world("tee"), encoding="cdr", lockstep=False) as robot:
        res = runner.invoke(app, ["drive", str(keep_left), "--connect", robot.url, "--scan", "/laser"])
    assert res.exit_code == 1
    _one_error_line(
        res.output, "the server advertises no scan on /laser (it has: /odom, /scan, /tf, /tf_static)"
    )
