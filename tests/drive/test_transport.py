"""The run over the transport seam, with an in-process robot behind it (``tests.support.fake_transport``).

The fake plugs into :func:`~lfdfuse.drive.lifecycle.run_live` as the Foxglove client does, and
nothing of the run changes for it: the closed loop, the stale-scan watchdog, the zero Twist on
every exit, the error of a robot never reached, the live log's clock.
"""

from __future__ import annotations

import ast
import json
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from lfdfuse.drive import lifecycle
from lfdfuse.drive.lifecycle import run_live
from lfdfuse.drive.options import DriveError, DriveOptions, DriveSummary, Stopper
from lfdfuse.log.reader import iter_messages
from lfdfuse.network.table import load_table
from lfdfuse.world.model import load_world
from tests.drive.conftest import in_thread
from tests.support.fake_transport import EPOCH_NS, FakeRobot

SLACK_S = 0.25  # this machine's scheduling (two cores shared by many processes)


def _run(
    robot: FakeRobot, table: Path, stopper: Stopper, *, out: Path | None = None, **kw: object
) -> tuple[DriveSummary, list[str]]:
    """``drive`` over the fake robot's transport, in this (the main) thread: signals reach it."""
    notes: list[str] = []
    opts = DriveOptions(table=load_table(table), url=robot.transport().url, **kw)  # type: ignore[arg-type]
    s = run_live(opts, robot.transport(), out=out, notify=notes.append, stopper=stopper)
    return s, notes


def _path_m(poses: list[tuple[float, float, float]]) -> float:
    p = np.array(poses)[:, :2]
    return float(np.hypot(*np.diff(p, axis=0).T).sum())


def test_keep_left_drives_tee_through_the_fake_transport(keep_left: Path, tmp_path: Path) -> None:
    out, stopper = tmp_path / "live.mcap", Stopper()
    robot = FakeRobot(load_world("tee"), 60.0, stopper=stopper)
    s, _ = _run(robot, keep_left, stopper, out=out)
    assert robot.tick == 600 and robot.collisions == 0 and s.ended == "robot done"
    assert _path_m(robot.poses) >= 10.0
    left, right = np.array(robot.sides).T
    assert np.mean(left) < 0.7 * np.mean(right), "keeps left"
    assert s.encoding == "fake Twist" and s.ticks >= 590 and s.connections == 1
    assert "attract_red" not in (s.behaviors.missing if s.behaviors else {})  # the fake has a camera
    assert robot.received[0].v_mps == 0.0 and robot.received[-1].v_mps == 0.0  # stands still first and last
    # the live log: what was sent, in order, and on the robot's clock from its first message on
    cmds = [(t, json.loads(d)) for _, _, t, d in iter_messages(out, topics=["/lfd/command"])]
    sent = [c["linear"]["x"] for _, c in cmds]
    assert np.allclose(sent, [r.v_mps for r in robot.received], atol=1e-6)
    first_scan = next(t for _, _, t, _ in iter_messages(out, topics=["/scan"]))
    assert first_scan == robot.stamps[0] and EPOCH_NS <= first_scan < EPOCH_NS + 1_000_000_000
    assert cmds[0][1]["source"] == "stale" and first_scan - 1_000_000_000 < cmds[0][0] < first_scan
    times = [t for _, _, t, _ in iter_messages(out)]
    assert min(times) > EPOCH_NS - 1_000_000_000 and times == sorted(times)


def test_stale_scans_stop_the_robot_within_half_a_second(keep_left: Path) -> None:
    stopper = Stopper()
    robot = FakeRobot(load_world("tee"), 4.0, stopper=stopper, lockstep=False)
    robot.pause_scans(1.5, 1.5)
    s, notes = _run(robot, keep_left, stopper)
    walls = np.array(robot.scan_walls)
    gap = int(np.argmax(np.diff(walls)))
    last, back = walls[gap], walls[gap + 1]
    assert 1.4 < back - last < 2.5  # 1.5 s of robot time without scans (and this machine's delays)
    rx = robot.received
    moving = [r for r in rx if r.wall_s < last]
    paused = [r for r in rx if last < r.wall_s < back]
    after = [r for r in rx if r.wall_s > back + 0.3]
    assert any(r.v_mps > 0.1 for r in moving)
    first_zero = next(r for r in paused if (r.v_mps, r.omega_rps) == (0.0, 0.0))
    assert first_zero.wall_s - last <= 0.5 + SLACK_S
    assert all((r.v_mps, r.omega_rps) == (0.0, 0.0) for r in paused if r.wall_s >= first_zero.wall_s)
    assert len([r for r in paused if r.wall_s >= first_zero.wall_s]) >= 5  # repeated while blind
    assert any(r.v_mps > 0.1 for r in after), "drives again once scans return"
    assert any("no fresh scan" in n for n in notes) and any("scans are back" in n for n in notes)
    assert s.zeros >= 6


@pytest.mark.parametrize("end", ["--duration", "signal SIGTERM"])
def test_the_run_ends_with_a_zero_twist(end: str, keep_left: Path, tmp_path: Path) -> None:
    out, stopper = tmp_path / "live.mcap", Stopper()
    robot = FakeRobot(load_world("tee"), 60.0, lockstep=False)

    def terminate() -> None:
        end_by = time.monotonic() + 20.0
        while len(robot.received) < 10 and time.monotonic() < end_by:
            time.sleep(0.01)
        os.kill(os.getpid(), signal.SIGTERM)  # the run's handler turns it into a clean stop

    th = in_thread(terminate) if end.startswith("signal") else None
    s, _ = _run(robot, keep_left, stopper, duration_s=1.5 if th is None else 30.0, out=out)
    if th is not None:
        th.join(5)
    assert s.ended == end and s.duration_s < 5.0 and (th is not None or s.duration_s >= 1.5)
    assert any(r.v_mps > 0.05 for r in robot.received)
    last = robot.received[-1]
    assert (last.v_mps, last.omega_rps) == (0.0, 0.0)
    cmds = [json.loads(d) for _, _, _, d in iter_messages(out, topics=["/lfd/command"])]
    assert cmds[-1]["source"] == "stop" and cmds[-1]["linear"]["x"] == 0.0 and cmds[-1]["sent"]


def test_a_robot_never_reached_is_an_error_and_leaves_no_file(keep_left: Path, tmp_path: Path) -> None:
    stopper = Stopper()
    robot = FakeRobot(load_world("tee"), 5.0, reachable=False)
    with pytest.raises(DriveError, match=r"^cannot connect to fake://robot: refused$"):
        _run(robot, keep_left, stopper, duration_s=0.8, out=tmp_path / "live.mcap")
    assert list(tmp_path.iterdir()) == []


def test_the_run_knows_no_protocol() -> None:
    """The lifecycle imports no transport: the seam is the only way to a robot."""
    tree = ast.parse(Path(lifecycle.__file__).read_text())
    names = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    names |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    protocol = {"websockets", "foxglove", "rosbags", "lfdfuse.drive.foxglove", "lfdfuse.drive.decoders"}
    assert not {n for n in names if any(n == p or n.startswith(p + ".") for p in protocol)}
    assert "lfdfuse.drive.transport" in names
