"""``lfdfuse inspect`` on robot logs: ROS bags summarised like ``ros2 bag info``
(topics, types, counts, time span) and what ``import`` would make of them."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.sources.importers import robot_format
from lfdfuse.sources.importers.convert import import_log
from lfdfuse.sources.importers.info import summarise
from tests.conftest import SHARED

REAL = SHARED / "realdata"
runner = CliRunner()
T0 = 1_700_000_000_123_456_789  # an epoch stamp, exact to the nanosecond


def _messages(ts: Any) -> dict[str, tuple[str, list[Any]]]:
    """topic → (type, messages) of a tiny drive: a static tf, 4 scans, 2 commands, 3 odometry poses."""
    T = ts.types
    V3, Q = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    stamp = T["builtin_interfaces/msg/Time"](sec=0, nanosec=0)

    def header(frame: str) -> Any:
        fields = {"stamp": stamp, "frame_id": frame}
        if "seq" in T["std_msgs/msg/Header"].__dataclass_fields__:  # ROS 1
            fields["seq"] = 0
        return T["std_msgs/msg/Header"](**fields)

    tf = T["geometry_msgs/msg/TransformStamped"](
        header=header("base_link"),
        child_frame_id="laser",
        transform=T["geometry_msgs/msg/Transform"](
            translation=V3(x=0.1, y=0.0, z=0.2), rotation=Q(x=0.0, y=0.0, z=0.0, w=1.0)
        ),
    )
    scan = T["sensor_msgs/msg/LaserScan"](
        header=header("laser"), angle_min=-math.pi / 2, angle_max=math.pi / 2, angle_increment=math.pi / 4,
        time_increment=0.0, scan_time=0.1, range_min=0.1, range_max=5.0,
        ranges=np.array([1.0, 2.0, np.inf, 3.0, 4.0], dtype=np.float32), intensities=np.zeros(0, dtype=np.float32),
    )  # fmt: skip
    twist = T["geometry_msgs/msg/Twist"](linear=V3(x=0.3, y=0.0, z=0.0), angular=V3(x=0.0, y=0.0, z=0.5))
    pose = T["geometry_msgs/msg/PoseWithCovariance"](
        pose=T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0),
            orientation=Q(x=0.0, y=0.0, z=0.0, w=1.0),
        ),
        covariance=np.zeros(36),
    )
    odom = T["nav_msgs/msg/Odometry"](
        header=header("odom"),
        child_frame_id="base_link",
        pose=pose,
        twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)),
    )
    return {
        "/tf_static": ("tf2_msgs/msg/TFMessage", [T["tf2_msgs/msg/TFMessage"](transforms=[tf])]),
        "/front/scan": ("sensor_msgs/msg/LaserScan", [scan] * 4),
        "/cmd_vel": ("geometry_msgs/msg/Twist", [twist] * 2),
        "/odom": ("nav_msgs/msg/Odometry", [odom] * 3),
    }


def write_bag(
    path: Path, *, ros1: bool = False, mcap: bool = False, topics: tuple[str, ...] | None = None
) -> None:
    """A tiny bag written with rosbags' own writer (ROS 1, or ROS 2 in sqlite3 or MCAP storage);
    message ``k`` of a topic is stamped ``T0 + k·0.1 s`` (+ 1 µs per topic, so stamps differ)."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    if "tf2_msgs/msg/TFMessage" not in ts.types:  # the Noetic store lacks it: a ROS 1 bag embeds it
        ts.register(
            get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage")
        )
    plugin = StoragePlugin.MCAP if mcap else StoragePlugin.SQLITE3
    writer = Writer1(path) if ros1 else Writer2(path, version=8, storage_plugin=plugin)
    with writer as w:
        for j, (topic, (msgtype, msgs)) in enumerate(_messages(ts).items()):
            if topics is not None and topic not in topics:
                continue
            conn = w.add_connection(topic, msgtype, typestore=ts)
            for k, m in enumerate(msgs):
                data = ts.serialize_ros1(m, msgtype) if ros1 else ts.serialize_cdr(m, msgtype)
                w.write(conn, T0 + k * 100_000_000 + j * 1000, data)


@pytest.mark.parametrize("kind", ["ros1", "sqlite3", "mcap"])
def test_a_small_bag_is_listed_and_its_import_foretold(kind: str, tmp_path: Path) -> None:
    bag = tmp_path / ("small.bag" if kind == "ros1" else "small")
    write_bag(bag, ros1=kind == "ros1", mcap=kind == "mcap")
    assert robot_format(bag) == ("ros1" if kind == "ros1" else "ros2")
    s = summarise(bag)
    assert {t.topic: (t.msgtype, t.count) for t in s.topics} == {
        "/cmd_vel": ("geometry_msgs/msg/Twist", 2),
        "/front/scan": ("sensor_msgs/msg/LaserScan", 4),
        "/odom": ("nav_msgs/msg/Odometry", 3),
        "/tf_static": ("tf2_msgs/msg/TFMessage", 1),
    }
    assert {t.serialization for t in s.topics} == {"ros1" if kind == "ros1" else "cdr"}
    assert s.storage == {"ros1": "ROS 1 bag v2.0", "sqlite3": "rosbag2 sqlite3", "mcap": "rosbag2 mcap"}[kind]
    assert s.messages == 10 and s.start_ns == T0 and s.end_ns == T0 + 3 * 100_000_000 + 1000  # exact
    assert s.plan.problem is None and s.plan.commands_from == "recorded on /cmd_vel"
    assert s.plan.topics == {"scan": "/front/scan", "cmd": "/cmd_vel", "odom": "/odom"}
    assert s.plan.mount is not None and math.isclose(s.plan.mount.x_m, 0.1)
    # the foretelling is the import's own choice
    done = import_log(bag, out=tmp_path / "demo.mcap")
    assert done.topics == s.plan.topics and done.commands_from == s.plan.commands_from
    assert (done.scans, done.commands, done.poses) == (4, 2, 3)

    res = runner.invoke(app, ["inspect", str(bag)])
    assert res.exit_code == 0, res.output
    out = res.stdout
    assert "2023-11-14 22:13:20.123 UTC (1700000000.123456789)" in out  # start, exact
    assert "messages:  10 on 4 topic(s)" in out
    assert "/scan     ← /front/scan (sensor_msgs/msg/LaserScan, 4)" in out
    assert "/cmd_vel  ← /cmd_vel (geometry_msgs/msg/Twist, 2), as recorded" in out
    assert "/pose     ← /odom (nav_msgs/msg/Odometry, 3)" in out
    assert f"lfdfuse import {bag} -o demo.mcap" in out


def test_a_bag_without_commands_or_scans_says_what_import_would_do(tmp_path: Path) -> None:
    odom_only = tmp_path / "odom"
    write_bag(odom_only, topics=("/front/scan", "/odom"))
    assert summarise(odom_only).plan.commands_from == "derived from odometry on /odom"
    no_scan = tmp_path / "noscan.bag"
    write_bag(no_scan, ros1=True, topics=("/cmd_vel", "/odom"))
    s = summarise(no_scan)
    assert s.plan.problem is not None and "LaserScan" in s.plan.problem
    res = runner.invoke(app, ["inspect", str(no_scan)])
    assert res.exit_code == 0 and "import would refuse it: the bag has no sensor_msgs/LaserScan" in res.stdout


def test_bad_bags_are_one_line_errors(tmp_path: Path) -> None:
    good = tmp_path / "good.bag"
    write_bag(good, ros1=True)
    folder = tmp_path / "folder"
    folder.mkdir()
    (folder / "metadata.yaml").write_text("rosbag2_bagfile_information: [\n")  # a YAML error spans lines
    cut = tmp_path / "cut.bag"
    cut.write_bytes(good.read_bytes()[:200])
    for path, why in (
        (folder, "cannot read the bag"),
        (cut, "cannot read the bag"),
    ):
        res = runner.invoke(app, ["inspect", str(path)])
        assert res.exit_code == 1, res.output
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: ") and why in lines[0], res.stderr
        assert "Traceback" not in res.output
    renamed = tmp_path / "renamed.dat"  # a ROS 1 bag is known by its header, not its name
    renamed.write_bytes(good.read_bytes())
    res = runner.invoke(app, ["inspect", str(renamed)])
    assert res.exit_code == 0 and "/cmd_vel  ← /cmd_vel (geometry_msgs/msg/Twist, 2)" in res.stdout


def _real(rel: str) -> Path:
    p = REAL / rel
    if not p.exists():
        pytest.skip("shared real data not present (../shared/realdata or $LFDFUSE_SHARED)")
    return p


@pytest.mark.parametrize(
    "rel",
    [
        "ros2/macfirst_floor_take_2",
        "ros2/macfirst_floor_take_2.mcap",
        "ros2/macfirst_floor_take_2/macfirst_floor_take_2_0.db3",
    ],
)
def test_the_real_turtlebot_bag_in_every_storage(rel: str) -> None:
    s = summarise(_real(rel))
    counts = {t.topic: t.count for t in s.topics}
    assert counts == {
        "/cmd_vel": 192, "/odom": 920, "/robot_description": 1, "/scan": 357, "/tf": 953, "/tf_static": 2
    }  # fmt: skip
    assert s.messages == 2425 and s.duration_s == pytest.approx(46.2, abs=0.05)
    assert s.plan.topics == {"scan": "/scan", "cmd": "/cmd_vel", "odom": "/odom"}
    assert s.plan.mount is not None and s.plan.mount.yaw_rad == pytest.approx(
        math.pi / 2, abs=1e-3
    )  # README: +90°
    res = runner.invoke(app, ["inspect", str(_real(rel))])
    assert res.exit_code == 0, res.output
    assert "/scan     ← /scan (sensor_msgs/msg/LaserScan, 357)" in res.stdout
    assert "2022-09-23 21:09:35.548 UTC" in res.stdout and "duration:  46.2 s" in res.stdout


def test_the_real_ros1_bags() -> None:
    neato = summarise(_real("ros1/neato-keyboard-middle.bag"))
    counts = {t.topic: t.count for t in neato.topics}
    assert (
        neato.messages == 2868
        and counts["/scan"] == 185
        and counts["/cmd_vel"] == 6
        and counts["/odom"] == 278
    )
    assert neato.duration_s == pytest.approx(37.1, abs=0.1)
    assert neato.plan.topics == {"scan": "/scan", "cmd": "/cmd_vel", "odom": "/odom"}
    assert neato.plan.mount is not None and abs(neato.plan.mount.yaw_rad) == pytest.approx(math.pi, abs=1e-3)
    still = summarise(_real("ros1/demo_stationary_simple_environment.bag"))
    assert [(t.topic, t.count) for t in still.topics] == [("/scan", 1265)]
    assert still.plan.topics == {"scan": "/scan"} and still.plan.commands_from.startswith("none")
    res = runner.invoke(app, ["inspect", str(_real("ros1/neato-keyboard-middle.bag"))])
    assert res.exit_code == 0, res.output
    # piped: every topic name whole, nothing cut to the screen
    assert "/camera/image_raw/compressed/parameter_descriptions" in res.stdout and "…" not in res.stdout


def test_an_mcap_rosbags_cannot_read_still_shows_its_channels(tmp_path: Path) -> None:
    """cdr messages under schemas that are not ROS 2 messages: the MCAP listing, and why import refuses."""
    from mcap.writer import Writer

    path = tmp_path / "odd.mcap"
    with path.open("wb") as f:
        w = Writer(f)
        w.start()
        schema = w.register_schema("foxglove.LaserScan", "jsonschema", b"{}")
        chan = w.register_channel("/scan", "cdr", schema)
        for k in range(3):
            w.add_message(chan, log_time=k, publish_time=k, data=b"\x00\x01")
        w.finish()
    assert robot_format(path) == "ros2"
    res = runner.invoke(app, ["inspect", str(path)])
    assert res.exit_code == 0, res.output
    assert "/scan" in res.stdout and "import would refuse it: cannot read the bag" in res.stdout
