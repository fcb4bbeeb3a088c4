"""``lfdfuse record``: a scripted person drives the DDS test robot with their own teleop (another
participant publishing on ``rt/cmd_vel``); ``record`` listens from this process, writes the demo
as ``import`` would, and a table learned from it keeps left in another building."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from lfdfuse.drive.options import Stopper
from lfdfuse.drive.ros2.url import ros2_url
from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.log.reader import file_info, iter_messages
from lfdfuse.record import RecordOptions, RecordSummary, record
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from lfdfuse.world.model import load_world
from tests.conftest import mcap_check
from tests.drive.conftest import in_thread
from tests.support.dds import LOOPBACK, own_domain, start_robot

STYLE = "avoid,wander_left,wander_right,wall_attract_left,wall_attract_right,sonar_avoid"
IMPORT_CHANNELS = {"/scan", "/cmd_vel", "/pose", "/tf"}


@pytest.fixture
def domain(monkeypatch: pytest.MonkeyPatch) -> Iterator[int]:
    monkeypatch.setenv("CYCLONEDDS_URI", LOOPBACK)
    with own_domain() as d:
        yield d


def test_record_a_person_over_dds_and_learn_keep_left(tmp_path: Path, domain: int) -> None:
    demo = tmp_path / "demo.mcap"
    stopper = Stopper()
    got: dict[str, RecordSummary] = {}
    robot = start_robot(
        domain,
        tmp_path / "robot.json",
        "--world",
        "building",
        "--person",
        "keep-left",
        "--seconds",
        "100",
        "--command-timeout",
        "0.2",
        "--speed",
        "3",  # 30 scans a second: a person's robot three times over (unpaced, a loaded machine lost samples)
        "--wait-for-listener",
    )
    try:
        robot.wait_ready()
        th = in_thread(
            lambda: got.update(s=record(RecordOptions(url=ros2_url(domain)), out=demo, stopper=stopper))
        )
        r = robot.result(300)
        stopper.stop("the person is done")
        th.join(60)
    finally:
        robot.stop()
    s = got["s"]
    assert r["collisions"] == 0 and r["ticks"] == 1000
    assert s.received["cmd"] >= 950 and s.received["scan"] >= 950
    # one link; the robot leaving at its end may be seen (and sought again) before the stop
    assert s.connections == 1 or (s.connections == 2 and set(s.warnings) == {"lost 1"}), s
    # import's channels and provenance, teacher: human, and who drove
    report = json.loads(mcap_check(demo))
    assert report["ok"] and set(report["counts"]) == IMPORT_CHANNELS
    meta = file_info(demo).metadata["lfdfuse"]
    assert meta["command"] == "record" and meta["teacher"] == "human" and meta["format"] == "ros2-dds"
    assert meta["source"] == ros2_url(domain) and meta["cmd_publisher"] == "teleop_twist_keyboard"
    assert meta["laser_mount_from"] == "tf (base_link → laser)"
    assert s.demo.commands_from == "recorded on /cmd_vel by teleop_twist_keyboard"
    # the commands are the person's, in the order the robot saw them
    sent = [json.loads(d)["linear"]["x"] for _, _, _, d in iter_messages(demo, topics=["/cmd_vel"])]
    assert max(sent) > 0.3
    # segment takes it directly; the table learned keeps left in another building
    seg = tmp_path / "demo.seg.mcap"
    segment_file(demo, out=seg, behaviors=STYLE, measure_lag=False)  # each command answers its scan
    table, _, _ = estimate_run(read_segmented(seg), opts=EstimateOptions(seed=1, method="nnls"), name="rec")
    res = run_table(
        ExecuteOptions(world=load_world("tee"), table=table, max_time_s=45.0),
        out=tmp_path / "run.mcap",
        command="execute",
    )
    rep = res.report
    assert rep["collisions"] == 0 and rep["path_length_m"] >= 10.0
    assert rep["left_range_mean_m"] < 0.7 * rep["right_range_mean_m"], rep
    assert np.isfinite(rep["left_range_mean_m"])


def test_record_through_a_foxglove_bridge(tmp_path: Path) -> None:
    """``--connect ws://…``: the same recorder through the Foxglove transport (a bridge-like robot
    that streams its own /cmd_vel, as foxglove_bridge does), the same demo."""
    from rosbags.typesys import Stores, get_typestore

    from lfdfuse.world.model import load_world
    from tests.support.bridge_sim import BridgeSim

    store = get_typestore(Stores.ROS2_HUMBLE)
    T = store.types
    demo = tmp_path / "demo.mcap"
    stopper = Stopper()
    got: dict[str, RecordSummary] = {}
    with BridgeSim(load_world("tee"), encoding="cdr", lockstep=False, cmd_stamped=True) as robot:
        th = in_thread(lambda: got.update(s=record(RecordOptions(url=robot.url), out=demo, stopper=stopper)))
        assert robot.wait_for_subscriber(publisher=False)

        def teleop() -> None:  # the person's commands, as the bridge streams the robot's /cmd_vel
            while not robot.stopped.is_set():
                v3 = T["geometry_msgs/msg/Vector3"]
                tw = T["geometry_msgs/msg/Twist"](v3(0.3, 0.0, 0.0), v3(0.0, 0.0, 0.2))
                head = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](0, 0), "base_link")
                msg = T["geometry_msgs/msg/TwistStamped"](head, tw)
                robot.channels["/cmd_vel"].log(
                    bytes(store.serialize_cdr(msg, "geometry_msgs/msg/TwistStamped"))
                )
                time.sleep(0.1)

        person = in_thread(teleop)
        robot.run(3.0)
        stopper.stop("done")
        th.join(30)
        robot.stopped.set()
        person.join(5)
    s = got["s"]
    assert s.received["scan"] >= 20 and s.received["cmd"] >= 20
    meta = file_info(demo).metadata["lfdfuse"]
    assert meta["format"] == "foxglove" and meta["teacher"] == "human" and meta["command"] == "record"
    assert meta["laser_mount_from"] == "tf (base_link → laser)"
    sent = {json.loads(d)["linear"]["x"] for _, _, _, d in iter_messages(demo, topics=["/cmd_vel"])}
    assert sent == {0.3}
    assert set(json.loads(mcap_check(demo))["counts"]) == IMPORT_CHANNELS
