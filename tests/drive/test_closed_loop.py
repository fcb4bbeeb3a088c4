"""Closed loops over the wire: the learned keep-left network drives a robot that speaks like a
ROS 2 bridge (CDR) or like lfdfuse's own server (JSON), and the real ``teleop --input foxglove``.

The bridge-like robot steps its simulator as soon as a command answers a scan (lockstep), so a
minute of robot time takes seconds; ``teleop`` runs in real time, so its loop is short.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from lfdfuse.log.reader import iter_messages
from lfdfuse.network.table import load_table
from lfdfuse.world.model import load_world
from tests.conftest import ROOT, mcap_check
from tests.drive.conftest import in_thread, start_drive
from tests.support.bridge_sim import BridgeSim

EXE = shutil.which("lfdfuse", path=str(Path(sys.executable).parent)) or shutil.which("lfdfuse")


def _path_m(poses: list[tuple[float, float, float]]) -> float:
    p = np.array(poses)[:, :2]
    return float(np.hypot(*np.diff(p, axis=0).T).sum())


@pytest.mark.parametrize("encoding", ["cdr", "json"])
def test_keep_left_learned_in_building_drives_tee_over_the_wire(
    encoding: str, keep_left: Path, tmp_path: Path
) -> None:
    out = tmp_path / "live.mcap"
    with BridgeSim(load_world("tee"), encoding=encoding, lockstep=True) as robot:
        live = start_drive(load_table(keep_left), robot.url, out=out)

        def sixty_seconds() -> None:
            assert robot.wait_for_subscriber()
            robot.run(60.0)
            live.stopper.stop("robot done")

        th = in_thread(sixty_seconds)
        s = live.join(120)
        th.join(5)
    assert len(robot.poses) == 600 and robot.collisions == 0
    assert _path_m(robot.poses) >= 10.0
    left, right = np.array(robot.sides).T
    assert np.mean(left) < 0.7 * np.mean(right), "keeps left"
    assert {r.encoding for r in robot.received} == {encoding}
    assert s.encoding == f"{encoding} geometry_msgs/msg/Twist" and s.ticks >= 590 and s.latency_ms is not None
    if encoding == "cdr":  # the scanner faces the robot's left: only tf says so
        assert s.mount_from == "tf (base_link → laser)"
        assert "attract_red" in (s.behaviors.missing if s.behaviors else {})
    report = json.loads(mcap_check(out))
    assert report["ok"] and report["outOfOrder"] == 0
    assert {
        "/scan",
        "/pose",
        "/tf",
        "/cmd_vel",
        "/lfd/behaviors",
        "/lfd/bac",
        "/lfd/step",
        "/lfd/fused",
        "/lfd/overlay",
        "/lfd/command",
    } <= set(report["counts"])
    # what was sent is what the robot got, in order (the last zero Twist came after it stopped)
    sent = [json.loads(d)["linear"]["x"] for _, _, _, d in iter_messages(out, topics=["/cmd_vel"])]
    got = [r.v_mps for r in robot.received]
    assert 0 <= len(sent) - len(got) <= 2 and sent[-1] == 0.0
    assert np.allclose(sent[: len(got)], got, atol=1e-9)


def test_shadow_moves_nothing(keep_left: Path) -> None:
    with BridgeSim(load_world("tee"), encoding="cdr", lockstep=False) as robot:
        live = start_drive(load_table(keep_left), robot.url, shadow=True)

        def two_seconds() -> None:
            assert robot.wait_for_subscriber(publisher=False)
            robot.run(1.5)
            live.stopper.stop("robot done")

        th = in_thread(two_seconds)
        s = live.join(30)
        th.join(5)
    assert robot.received == [] and robot.listener.channels == {}  # not even advertised
    assert s.sent == 0 and s.ticks > 5
    assert _path_m(robot.poses) == 0.0


@pytest.mark.skipif(EXE is None, reason="the lfdfuse command is not installed")
def test_drive_the_real_teleop_server_then_sigterm(keep_left: Path, tmp_path: Path) -> None:
    """The real commands, each its own process: ``teleop --input foxglove`` is the robot,
    ``drive`` its only client; SIGTERM ends drive with a zero Twist and a whole MCAP."""
    assert EXE is not None
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    demo, live_log = tmp_path / "teleop.mcap", tmp_path / "live.mcap"
    teleop = subprocess.Popen(
        [EXE, "teleop", "--input", "foxglove", "--port", "0", "--world", "tee", "-o", str(demo)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert teleop.stdout is not None
        url = ""
        while not url:
            line = teleop.stdout.readline()
            assert line, teleop.stderr.read() if teleop.stderr else ""
            m = re.search(r"ws://[\d.]+:\d+", line)
            url = m.group(0) if m else ""
        drive = subprocess.Popen(
            [EXE, "drive", str(keep_left), "--connect", url, "--odom", "/pose", "-o", str(live_log)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        assert drive.stderr is not None
        notes = [drive.stderr.readline() for _ in range(2)]  # "drive … → url", "behaviours: …"
        assert "behaviours: avoid" in notes[-1], notes
        # 10 s: on a fresh install both processes compile their kernels (cached on disk) during
        # their first seconds, and the robot's scans wait for it
        time.sleep(10.0)
        drive.send_signal(signal.SIGTERM)
        d_out, d_err = drive.communicate(timeout=30)
        time.sleep(0.5)  # teleop applies the zero Twist at its next tick
        teleop.send_signal(signal.SIGINT)
        t_out, _ = teleop.communicate(timeout=30)
    finally:
        for p in (teleop,):
            if p.poll() is None:
                p.kill()
    assert drive.returncode == 0, d_err
    assert "ended       signal SIGTERM" in d_out
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []
    report = json.loads(mcap_check(live_log))
    assert report["ok"] and report["counts"]["/lfd/command"] > 30
    commands = [json.loads(d) for _, _, _, d in iter_messages(live_log, topics=["/lfd/command"])]
    assert commands[-1]["source"] == "stop" and commands[-1]["linear"]["x"] == 0.0
    # the robot's side: it drove, kept left, did not collide, and got the zero Twist last
    poses = [json.loads(d)["pose"]["position"] for _, _, _, d in iter_messages(demo, topics=["/pose"])]
    xy = np.array([(p["x"], p["y"]) for p in poses])
    assert np.hypot(*np.diff(xy, axis=0).T).sum() > 1.5
    inputs = [json.loads(d) for _, _, _, d in iter_messages(demo, topics=["/teleop/input"])]
    assert inputs and (inputs[-1]["v_mps"], inputs[-1]["omega_rps"]) == (0.0, 0.0)
    assert re.search(r"collisions\s+0\b", t_out), t_out
    scans = [json.loads(d)["ranges"] for _, _, _, d in iter_messages(demo, topics=["/scan"])]
    left, right = np.array([(r[-1], r[0]) for r in scans[10:]]).T
    assert np.mean(left) < np.mean(right)


def test_commands_never_exceed_the_clamp(keep_left: Path) -> None:
    with BridgeSim(load_world("tee"), encoding="cdr", lockstep=True) as robot:
        live = start_drive(load_table(keep_left), robot.url, max_speed=0.15, max_turn=0.5)

        def ten_seconds() -> None:
            assert robot.wait_for_subscriber()
            robot.run(10.0)
            live.stopper.stop("robot done")

        th = in_thread(ten_seconds)
        s = live.join(60)
        th.join(5)
    v = np.array([r.v_mps for r in robot.received])
    w = np.array([r.omega_rps for r in robot.received])
    assert len(v) >= 95 and np.all(np.abs(v) <= 0.15) and np.all(np.abs(w) <= 0.5)
    assert v.max() == pytest.approx(0.15, abs=1e-4) and s.limits.v_max_mps == 0.15  # it drives at the clamp
    assert _path_m(robot.poses) > 1.0 and robot.collisions == 0


def test_a_twist_stamped_robot_gets_twist_stamped(keep_left: Path) -> None:
    """ROS 2 Jazzy robots take ``TwistStamped`` on /cmd_vel: drive sends the type advertised there,
    stamped with the robot's clock (the scan's stamp)."""
    with BridgeSim(load_world("tee"), encoding="cdr", lockstep=True, cmd_stamped=True) as robot:
        live = start_drive(load_table(keep_left), robot.url)

        def five_seconds() -> None:
            assert robot.wait_for_subscriber()
            robot.run(5.0)
            live.stopper.stop("robot done")

        th = in_thread(five_seconds)
        s = live.join(60)
        th.join(5)
    assert s.encoding == "cdr geometry_msgs/msg/TwistStamped" and robot.listener.bad == 0
    # it drives (1.82 m on a quiet machine; on a loaded machine the watchdog's zero Twists,
    # sent when a scan's command took over 0.5 s of wall time, stop some of the lockstep ticks)
    assert len(robot.received) >= 45 and _path_m(robot.poses) > 0.5
    # zero Twists before the first scan (a new connection's, the watchdog's) carry our clock, as
    # nothing else is known; every later command the robot's (the simulated robot's starts at 0)
    stamps = robot.listener.stamps
    k = next(i for i, t in enumerate(stamps) if t < 10**15)
    assert 1 <= k <= 5 and all(t > 10**18 for t in stamps[:k])
    assert stamps[k:] == sorted(stamps[k:]) and stamps[-1] <= 5_100_000_000


@pytest.mark.skipif(EXE is None, reason="the lfdfuse command is not installed")
def test_shadow_watches_what_drives_the_teleop_robot_on_one_machine(keep_left: Path, tmp_path: Path) -> None:
    """``teleop --input foxglove`` streams the command driving its robot on /cmd_vel, as a robot's
    bridge does: one ``drive`` drives it, a second ``drive --shadow`` with the same table watches
    and agrees with what it sees (both are the same network on nearly the same scans)."""
    assert EXE is not None
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    teleop = subprocess.Popen(
        [EXE, "teleop", "--input", "foxglove", "--port", "0", "--world", "tee", "--duration", "30"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        cwd=tmp_path,
    )
    try:
        assert teleop.stdout is not None
        url = ""
        while not url:
            line = teleop.stdout.readline()
            assert line, teleop.stderr.read() if teleop.stderr else ""
            m = re.search(r"ws://[\d.]+:\d+", line)
            url = m.group(0) if m else ""
        table = load_table(keep_left)
        driver = start_drive(table, url, odom_topic="/pose")
        watcher = start_drive(table, url, odom_topic="/pose", shadow=True)
        time.sleep(4.0)
        for live in (watcher, driver):
            live.stopper.stop("test done")
        seen, drove = watcher.join(), driver.join()
    finally:
        teleop.send_signal(signal.SIGINT)
        teleop.communicate(timeout=30)
    assert drove.sent > 10 and seen.sent == 0
    assert seen.agreement_deg is not None and seen.agreement_ticks > 10, seen
    assert seen.agreement_deg < 15.0, seen
