"""``drive --ros2`` over real DDS on the loopback: the robot is another process (the simulator behind
ROS 2's names, types and QoS, :mod:`tests.support.dds_robot`), drive a participant of its own.

The closed loop runs in lockstep (the robot steps as soon as a command answers a scan: a minute
of robot time in seconds); the faults run the robot in real time (10 Hz), times on the
machine's monotonic clock, which both processes share. Tolerances beyond the contract's 0.5 s
allow for this machine's scheduling (two cores shared by many processes).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from lfdfuse.drive.options import DriveError
from lfdfuse.drive.ros2.url import ros2_url
from lfdfuse.log.reader import iter_messages
from lfdfuse.network.table import load_table
from tests.conftest import ROOT, mcap_check
from tests.drive.conftest import start_drive
from tests.support.dds import LOOPBACK, own_domain, start_robot

EXE = shutil.which("lfdfuse", path=str(Path(sys.executable).parent)) or shutil.which("lfdfuse")
SLACK_S = 0.25


@pytest.fixture
def domain(monkeypatch: pytest.MonkeyPatch) -> Iterator[int]:
    monkeypatch.setenv("CYCLONEDDS_URI", LOOPBACK)
    with own_domain() as d:
        yield d


def _path_m(poses: list[list[float]]) -> float:
    p = np.array(poses)[:, :2]
    return float(np.hypot(*np.diff(p, axis=0).T).sum())


def _zero(c: list[float]) -> bool:
    return (c[2], c[3]) == (0.0, 0.0)


def test_keep_left_drives_tee_over_dds(keep_left: Path, tmp_path: Path, domain: int) -> None:
    out = tmp_path / "live.mcap"
    robot = start_robot(
        domain,
        tmp_path / "robot.json",
        "--world",
        "tee",
        "--seconds",
        "60",
        "--lockstep",
        "--wait-for-driver",
    )
    try:
        robot.wait_ready()
        live = start_drive(load_table(keep_left), ros2_url(domain), out=out)
        r = robot.result()
        live.stopper.stop("robot done")
        s = live.join(60)
    finally:
        robot.stop()
    assert r["ticks"] == 600 and r["collisions"] == 0
    assert _path_m(r["poses"]) >= 10.0
    left, right = np.array(r["sides"]).T
    assert np.mean(left) < 0.7 * np.mean(right), "keeps left"
    assert s.encoding == "cdr geometry_msgs/msg/Twist" and s.ticks >= 590 and s.latency_ms is not None
    assert s.mount_from == "tf (base_link → laser)", "the latched /tf_static said where the laser sits"
    assert all(k.startswith("lost") for k in s.warnings), "no warning but the robot leaving at its end"
    report = json.loads(mcap_check(out))
    assert report["ok"] and {"/scan", "/pose", "/cmd_vel", "/lfd/behaviors", "/lfd/command"} <= set(
        report["counts"]
    )
    sent = [json.loads(d)["linear"]["x"] for _, _, _, d in iter_messages(out, topics=["/cmd_vel"])]
    got = [c[2] for c in r["received"]]
    moving, reached = [v for v in sent if v], [v for v in got if v]
    # in order; the answer to the robot's last scan may come after the robot stopped listening
    assert moving[: len(reached)] == reached and len(moving) - len(reached) <= 1, (
        "the network's commands reached the robot, in order"
    )
    assert len(sent) >= len(got) and sent[-1] == 0.0


def test_scans_stop_the_robot_stops_within_half_a_second(
    keep_left: Path, tmp_path: Path, domain: int
) -> None:
    robot = start_robot(
        domain,
        tmp_path / "robot.json",
        "--seconds",
        "5.5",
        "--pause-at",
        "2",
        "--pause-for",
        "1.5",
        "--wait-for-driver",
    )
    try:
        robot.wait_ready()
        live = start_drive(load_table(keep_left), ros2_url(domain))
        r = robot.result()
        live.stopper.stop("done")
        s = live.join(60)
    finally:
        robot.stop()
    marks, rx = r["marks"], r["received"]
    before = [c for c in rx if c[0] < marks["pause"]]
    paused = [c for c in rx if marks["pause"] <= c[0] < marks["back"]]
    after = [c for c in rx if c[0] > marks["back"] + 0.5]
    assert any(c[2] > 0.1 for c in before)
    first_zero = next(c for c in paused if _zero(c))
    assert first_zero[0] - marks["pause"] <= 0.5 + SLACK_S
    assert all(_zero(c) for c in paused if c[0] >= first_zero[0])
    assert any(c[2] > 0.1 for c in after), "drives again once scans return"
    assert any("no fresh scan" in n for n in live.notes) and any("scans are back" in n for n in live.notes)
    assert s.zeros >= 5


def test_the_robot_restarts_drive_finds_it_again(keep_left: Path, tmp_path: Path, domain: int) -> None:
    """The robot's process ends and another starts: drive rediscovers it; while none is there,
    nothing but zero Twists goes out (a spy participant hears every command on rt/cmd_vel),
    the new link's first among them. (Whether the new robot hears that first zero depends on
    discovery: a volatile writer's sample reaches the readers matched by then, and drive waits
    only for the subscribers discovered so far.)

    The spy polls its reader from a thread: a Python listener on a reader of a topic this
    process also writes can deadlock the binding (the writer holds the GIL while it delivers
    locally and waits for the listener, which waits for the GIL)."""
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from lfdfuse.robot import idl

    heard: list[tuple[float, float, float]] = []
    spy = DomainParticipant(domain)
    qos = Qos(Policy.Reliability.Reliable(100_000_000), Policy.History.KeepLast(100))
    reader = DataReader(spy, Topic(spy, "rt/cmd_vel", idl.Twist), qos=qos)
    listening = threading.Event()
    listening.set()

    def poll() -> None:
        while listening.is_set():
            now = time.monotonic()
            # (a writer that leaves is an invalid sample: no data)
            heard.extend(
                (now, m.linear.x, m.angular.z) for m in reader.take(N=64) if isinstance(m, idl.Twist)
            )
            time.sleep(0.01)

    spying = threading.Thread(target=poll, daemon=True)
    spying.start()
    first = start_robot(domain, tmp_path / "one.json", "--seconds", "3", "--wait-for-driver")
    second = None
    try:
        first.wait_ready()
        live = start_drive(load_table(keep_left), ros2_url(domain))
        r1 = first.result()
        time.sleep(1.0)
        second = start_robot(domain, tmp_path / "two.json", "--seconds", "3", "--wait-for-driver")
        second.wait_ready()
        r2 = second.result()
        live.stopper.stop("done")
        s = live.join(60)
    finally:
        listening.clear()
        spying.join(5)
        first.stop()
        if second is not None:
            second.stop()
    # each robot's leaving is a lost link (the second's at the end of the test)
    assert s.connections >= 2 and any("reconnected" in n for n in live.notes), live.notes
    assert sum("connection lost (no publisher of /scan is left)" in n for n in live.notes) == 2
    gone, back = r1["marks"]["end"], r2["published"][0]
    while_gone = [c for c in heard if gone < c[0] < back]
    assert while_gone, "the old link's stop and the new link's start are heard"
    assert all((v, w) == (0.0, 0.0) for _, v, w in while_gone), "no command while the robot is gone"
    assert any(c[2] > 0.1 for c in r2["received"]), "drives the new robot"


def test_a_malformed_sample_is_one_warning_and_twist_stamped_is_sent(
    keep_left: Path, tmp_path: Path, domain: int
) -> None:
    """Samples on rt/scan that are no LaserScan: bytes that are no CDR of the type never arrive
    (Cyclone DDS drops them), three well-formed ones that are no scan are one warning, counted, and
    the run goes on. The robot's rt/cmd_vel subscriber is TwistStamped: drive publishes that."""
    robot = start_robot(
        domain,
        tmp_path / "robot.json",
        "--seconds",
        "3.5",
        "--malformed-at",
        "1.5",
        "--cmd-stamped",
        "--wait-for-driver",
    )
    try:
        robot.wait_ready()
        live = start_drive(load_table(keep_left), ros2_url(domain))
        r = robot.result()
        live.stopper.stop("done")
        s = live.join(60)
    finally:
        robot.stop()
    # (the robot leaving at its end is a lost link: not this test's business)
    warnings = [n for n in live.notes if n.startswith("warning:") and "connection lost" not in n]
    assert len(warnings) == 1 and "/scan: a malformed LaserScan" in warnings[0], live.notes
    assert [n for k, n in s.warnings.items() if not k.startswith("lost")] == [3]
    assert s.encoding == "cdr geometry_msgs/msg/TwistStamped"
    assert any(c[2] > 0.1 for c in r["received"] if c[0] > r["marks"]["bad"] + 0.3)


def test_shadow_publishes_nothing_and_measures_agreement(
    keep_left: Path, tmp_path: Path, domain: int
) -> None:
    """A person drives the robot with their own teleop participant; ``--shadow`` listens to their
    rt/cmd_vel beside the scans and publishes nothing: the robot hears only the person."""
    robot = start_robot(
        domain,
        tmp_path / "robot.json",
        *("--person", "keep-left", "--seconds", "8", "--command-timeout", "0.2", "--wait-for-listener"),
    )
    try:
        robot.wait_ready()
        live = start_drive(load_table(keep_left), ros2_url(domain), shadow=True)
        r = robot.result()
        live.stopper.stop("done")
        s = live.join(60)
    finally:
        robot.stop()
    assert s.sent == 0 and s.encoding == ""
    assert len(r["received"]) == r["ticks"], "one command a tick: the person's, and nothing of drive's"
    assert s.agreement_ticks > 20 and s.agreement_deg is not None


def test_another_type_or_an_incompatible_qos_is_one_line(keep_left: Path, domain: int) -> None:
    """A /scan of another type and a /tf_static that is not latched: a line each, and the run
    that never finds its scan says what it saw."""
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    from lfdfuse.robot import idl

    dp = DomainParticipant(domain)
    volatile = Qos(Policy.Reliability.Reliable(100_000_000), Policy.Durability.Volatile)
    _scan = DataWriter(dp, Topic(dp, "rt/scan", idl.Twist))
    _static = DataWriter(dp, Topic(dp, "rt/tf_static", idl.TFMessage), qos=volatile)
    live = start_drive(load_table(keep_left), ros2_url(domain))
    with pytest.raises(
        DriveError, match=r"/scan \(rt/scan\) in DDS domain \d+ is published as geometry_msgs/msg/Twist"
    ):
        live.join(30)
    warnings = [n for n in live.notes if n.startswith("warning:")]
    assert any("/scan" in w and "geometry_msgs/msg/Twist" in w for w in warnings), live.notes
    assert any("/tf_static: a publisher's QoS cannot match ours (durability" in w for w in warnings), (
        live.notes
    )
    assert len(warnings) == 2, live.notes


@pytest.mark.skipif(EXE is None, reason="the lfdfuse command is not installed")
def test_drive_ros2_command_then_sigterm(keep_left: Path, tmp_path: Path, domain: int) -> None:
    """The real command against the robot process; SIGTERM ends it with a zero Twist, exit 0."""
    assert EXE is not None
    robot = start_robot(domain, tmp_path / "robot.json", "--seconds", "30", "--wait-for-driver")
    live_log = tmp_path / "live.mcap"
    try:
        robot.wait_ready()
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        drive = subprocess.Popen(
            [EXE, "drive", str(keep_left), "--ros2", "--domain", str(domain), "-o", str(live_log)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        assert drive.stderr is not None
        notes = [drive.stderr.readline() for _ in range(2)]  # "drive … → ros2://domain/N", "behaviours: …"
        assert f"ros2://domain/{domain}" in notes[0] and "behaviours: avoid" in notes[1], notes
        time.sleep(3.0)
        drive.send_signal(signal.SIGTERM)
        d_out, d_err = drive.communicate(timeout=30)
        time.sleep(0.3)
        robot.proc.send_signal(signal.SIGTERM)
        r = robot.result()
    finally:
        robot.stop()
    assert drive.returncode == 0, d_err
    assert "ended       signal SIGTERM" in d_out and "(cdr geometry_msgs/msg/Twist)" in d_out
    rx = r["received"]
    assert any(c[2] > 0.1 for c in rx) and _zero(rx[-1]), "drove, and got the zero Twist last"
    report = json.loads(mcap_check(live_log))
    assert report["ok"]
    commands = [json.loads(d) for _, _, _, d in iter_messages(live_log, topics=["/lfd/command"])]
    assert commands[-1]["source"] == "stop" and commands[-1]["linear"]["x"] == 0.0


def test_the_robot_is_named_once(keep_left: Path) -> None:
    """``--connect URL`` or ``--ros2 [--domain N]``: exactly one; anything else is bad usage (exit 2)."""
    from typer.testing import CliRunner

    from lfdfuse.cli.main import app

    for args, said in (
        ([], "give either --connect ws://HOST:PORT or --ros2"),
        (["--ros2", "--connect", "ws://127.0.0.1:9"], "give either --connect ws://HOST:PORT or --ros2"),
        (["--connect", "ws://127.0.0.1:9", "--domain", "3"], "--domain is a --ros2 option"),
    ):
        res = CliRunner().invoke(app, ["drive", str(keep_left), *args])
        assert res.exit_code == 2 and said in " ".join(res.output.split()), (args, res.output)
    res = CliRunner().invoke(app, ["record", "-o", "x.mcap"])
    assert res.exit_code == 2 and "give either --connect ws://HOST:PORT or --ros2" in res.output
