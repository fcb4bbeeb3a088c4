"""The cases a corpus of real drives brings to ``import``: a rosbag2 folder named like a ROS 1 bag,
limits of a controller that mostly turned slowly, discrete and continuous commands told apart by
their structure, two nodes publishing on one ``/cmd_vel``, ROS 1 frames with a leading slash.
Each on the real log that shows it (skipped without ``../shared``) and on a bag written here."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from lfdfuse.log.reader import file_info
from lfdfuse.robot.commands import classify_commands, percentile_limit
from lfdfuse.sources.importers import detect_format, robot_format
from lfdfuse.sources.importers.convert import ImportOptions, import_log
from lfdfuse.sources.importers.records import SourceError, TopicChoice
from tests.conftest import SHARED

REAL = SHARED / "realdata"
SIM_FOLDER = "simulated/AnmolRattanSingh__comprobo_warmup_project/bags/test_drive.bag"
PERSON_FOLLOWER = (
    "controllers/isaacvandor__comprobo_warmup_project/warmup_project/bags/person_follower_demo.bag"
)
WALL_TWO_PUBLISHERS = "controllers/paulruvolo__warmup_project_2017/bags/wall_follow_2017-01-29-20-38-37.bag"
WALL_PROPORTIONAL = "controllers/zneb97__comprobo_warmup_project/bags/wallFollowerBagLeft.bag"
WALL_BANG_BANG = "controllers/EarlJr53__comprobo-warmup/bags/wall_follower_real"
GAMEPAD = "human/paulruvolo__warmup_project_2017/warmup_project/bags/teleop_2017-01-25-22-44-37.bag"
KEYBOARDS = (
    "human/paulruvolo__warmup_project_2017/warmup_project/bags/test_drive.bag",
    "human/SeanCCarter__warmup_project_2017/bags/first_bag.bag",
    "human/zneb97__comprobo_warmup_project/bags/firstBag.bag",
    "human/GGRice__comprobo_warmup_project/bags/rosbag_first_test_2018-09-11-15-04-53.bag",
    "human/xiaofanwu__comprobo15/getting_familiar/2015-09-12-22-22-25.bag",
    "human/Brooks-Willis__Comprobo_Mobile_Project/drive1_a_fast.bag",
    "human/Brooks-Willis__Comprobo_Mobile_Project/drive2_a_slow.bag",
    "human/Brooks-Willis__Comprobo_Mobile_Project/drive3_a_wall.bag",
    "human/Cbabe__NeatoWarmUpProject/Bags/teleop_bag_v2",
    "human/yycho0108__comprobo_warmup_project/warmup_project/bags/test_drive.bag",
    "ros1/neato-keyboard-middle.bag",
    "ros2/macfirst_floor_take_2",
)


def _real(rel: str) -> Path:
    p = REAL / rel
    if not p.exists():
        pytest.skip("shared real data not present (../shared/realdata or $LFDFUSE_SHARED)")
    return p


# --- bags written here ---------------------------------------------------------------------------


def _msgs(store: str) -> tuple[Any, Any]:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE if store == "ros2" else Stores.ROS1_NOETIC)
    if "tf2_msgs/msg/TFMessage" not in ts.types:  # Noetic's store has no tf2_msgs
        ts.register(
            get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage")
        )
    return ts, ts.types


def _scan(T: Any, frame: str, ros2: bool) -> object:
    stamp = T["builtin_interfaces/msg/Time"](sec=0, nanosec=0)
    hdr = (
        T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)
        if ros2
        else T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
    )
    return T["sensor_msgs/msg/LaserScan"](
        header=hdr, angle_min=-math.pi / 2, angle_max=math.pi / 2, angle_increment=math.pi / 4,
        time_increment=0.0, scan_time=0.1, range_min=0.1, range_max=10.0,
        ranges=np.array([1.0, 2.0, 3.0, 4.0, 5.0], dtype=np.float32), intensities=np.zeros(0, dtype=np.float32),
    )  # fmt: skip


def _twist(T: Any, v: float, w: float) -> object:
    vec = T["geometry_msgs/msg/Vector3"]
    return T["geometry_msgs/msg/Twist"](linear=vec(x=v, y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=w))


def _tf(T: Any, parent: str, child: str, x: float, yaw: float, ros2: bool) -> object:
    stamp = T["builtin_interfaces/msg/Time"](sec=0, nanosec=0)
    hdr = (
        T["std_msgs/msg/Header"](stamp=stamp, frame_id=parent)
        if ros2
        else T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=parent)
    )
    tr = T["geometry_msgs/msg/Transform"](
        translation=T["geometry_msgs/msg/Vector3"](x=x, y=0.0, z=0.1),
        rotation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
    )
    msg = T["geometry_msgs/msg/TransformStamped"](header=hdr, child_frame_id=child, transform=tr)
    return T["tf2_msgs/msg/TFMessage"](transforms=[msg])


T0 = 1_700_000_000_000_000_000


def ros1_bag(
    path: Path, *, publishers: dict[str, list[tuple[float, float, float]]], slash: bool = False
) -> Path:
    """A ROS 1 bag: 10 scans at 10 Hz, a tf from the base to the laser (0.1 m behind, turned π), and
    for each publisher (callerid) its commands ``(t_s, v, ω)`` on ``/cmd_vel``; ``slash``: every
    frame id with a leading slash, as ROS 1 drivers wrote them."""
    from rosbags.rosbag1 import Writer

    ts, T = _msgs("ros1")
    s = "/" if slash else ""
    with Writer(path) as w:
        c_tf = w.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts)
        c_scan = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ts)
        conns = {
            name: w.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=ts, callerid=name)
            for name in publishers
        }
        tf = _tf(T, f"{s}base_link", f"{s}base_laser_link", -0.1, math.pi, ros2=False)
        w.write(c_tf, T0, ts.serialize_ros1(tf, "tf2_msgs/msg/TFMessage"))
        for k in range(10):
            scan = _scan(T, f"{s}base_laser_link", ros2=False)
            w.write(c_scan, T0 + k * 100_000_000 + 1, ts.serialize_ros1(scan, "sensor_msgs/msg/LaserScan"))
        for name, cmds in publishers.items():
            for t_s, v, om in cmds:
                raw = ts.serialize_ros1(_twist(T, v, om), "geometry_msgs/msg/Twist")
                w.write(conns[name], T0 + round(t_s * 1e9) + 2, raw)
    return path


def ros2_folder(path: Path) -> Path:
    """A rosbag2 folder (``metadata.yaml`` + ``.db3``): 5 scans and 5 commands."""
    from rosbags.rosbag2 import Writer

    ts, T = _msgs("ros2")
    with Writer(path, version=8) as w:
        c_scan = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ts)
        c_cmd = w.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=ts)
        for k in range(5):
            t = T0 + k * 100_000_000
            w.write(
                c_scan, t, ts.serialize_cdr(_scan(T, "base_link", ros2=True), "sensor_msgs/msg/LaserScan")
            )
            w.write(c_cmd, t + 1, ts.serialize_cdr(_twist(T, 0.2, 0.5 * (k % 2)), "geometry_msgs/msg/Twist"))
    return path


# --- rosbag2 folders by their content -------------------------------------------------------------


def test_a_rosbag2_folder_named_like_a_ros1_bag_imports(tmp_path: Path) -> None:
    bag = ros2_folder(tmp_path / "test_drive.bag")
    assert bag.is_dir() and (bag / "metadata.yaml").is_file()
    assert detect_format(bag) == "ros2" and robot_format(bag) == "ros2"
    s = import_log(bag, out=tmp_path / "o.mcap")
    assert (s.format, s.scans, s.commands) == ("ros2", 5, 5)


def test_a_ros1_bag_not_named_bag_imports(tmp_path: Path) -> None:
    bag = ros1_bag(tmp_path / "drive.bag", publishers={"/teleop": [(0.0, 0.3, 0.0), (0.5, 0.0, 1.0)]})
    renamed = bag.rename(tmp_path / "drive_2017-01-25.rec")
    assert detect_format(renamed) == "ros1"
    s = import_log(renamed, out=tmp_path / "o.mcap")
    assert (s.format, s.scans, s.commands) == ("ros1", 10, 2)


def test_the_simulated_rosbag2_folder_named_test_drive_bag_imports(tmp_path: Path) -> None:
    bag = _real(SIM_FOLDER)
    assert bag.is_dir() and bag.suffix == ".bag"
    s = import_log(bag, out=tmp_path / "o.mcap")
    assert (s.format, s.scans, s.commands) == ("ros2", 151, 20)


# --- limits from robust percentiles ---------------------------------------------------------------


def test_the_limit_is_the_range_not_the_mode_and_not_a_wild_command() -> None:
    mostly_slow = np.concatenate([np.full(300, 0.1), np.linspace(0.2, 1.6, 200), [1.8, -1.8]])
    assert percentile_limit(mostly_slow) == 1.8
    wild = np.concatenate([np.full(40, 0.3), np.zeros(20), [19.9]])
    assert percentile_limit(wild) == 0.3
    assert percentile_limit(np.zeros(5)) == 0.0 and percentile_limit(np.array([np.nan])) is None


def test_the_person_follower_turn_rate_is_its_range(tmp_path: Path) -> None:
    s = import_log(_real(PERSON_FOLLOWER), out=tmp_path / "o.mcap")
    assert s.omega_max_rps is not None and 1.7 < s.omega_max_rps < 1.9  # it turned at up to 1.8 rad/s
    assert s.v_max_mps is not None and 0.5 < s.v_max_mps < 0.55
    assert file_info(tmp_path / "o.mcap").metadata["lfdfuse"]["omega_max_rps"] == repr(s.omega_max_rps)


# --- discrete or continuous, by structure --------------------------------------------------------


def test_structure_tells_keys_from_smooth_commands() -> None:
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.3, 2.0, 80) * 1e9).astype(np.int64)
    # a keyboard with speed keys: six speed levels, but every change a jump between keys
    speeds = 0.2 * 1.1 ** rng.integers(0, 6, 80)
    keys = rng.integers(-1, 2, 80)
    k = classify_commands(t, speeds * (keys != 0), 1.0 * keys)
    assert k.model == "discrete" and k.levels > 4
    # a proportional controller at 10 Hz: many values, each a small step from the last
    t10 = np.arange(300, dtype=np.int64) * 100_000_000
    w = 0.5 * np.sin(np.linspace(0, 6, 300)) + rng.normal(0, 0.005, 300)
    c = classify_commands(t10, np.full(300, 0.1), w)
    assert c.model == "continuous" and c.levels > 20 and c.step < 0.1
    assert "continuous" in c.describe() and "distinct" in c.describe()


@pytest.mark.parametrize("rel", KEYBOARDS)
def test_keyboards_are_discrete(rel: str, tmp_path: Path) -> None:
    s = import_log(_real(rel), out=tmp_path / "o.mcap")
    assert s.command_model is not None and s.command_model.model == "discrete"
    assert file_info(tmp_path / "o.mcap").metadata["lfdfuse"]["command_model"] == "discrete"


@pytest.mark.parametrize(
    ("rel", "model"),
    [
        (WALL_PROPORTIONAL, "continuous"),  # 22 distinct ω
        (WALL_TWO_PUBLISHERS, "continuous"),
        (PERSON_FOLLOWER, "continuous"),
        (GAMEPAD, "continuous"),
        (WALL_BANG_BANG, "discrete"),  # three commands, switched
    ],
)
def test_controllers_and_the_gamepad_by_structure(rel: str, model: str, tmp_path: Path) -> None:
    s = import_log(_real(rel), out=tmp_path / "o.mcap")
    assert s.command_model is not None and s.command_model.model == model


# --- several publishers on one topic --------------------------------------------------------------


def test_two_publishers_are_named_merged_by_default_and_one_can_be_kept(tmp_path: Path) -> None:
    follower = [(0.1 * k, 0.5, 0.01 * k) for k in range(8)]
    bag = ros1_bag(tmp_path / "two.bag", publishers={"/wall_follow": follower, "/teleop": [(0.85, 0.0, 0.0)]})
    s = import_log(bag, out=tmp_path / "merged.mcap")
    assert s.commands == 9 and [(p.name, p.count) for p in s.publishers] == [
        ("/teleop", 1),
        ("/wall_follow", 8),
    ]
    assert any("2 publishers on /cmd_vel, merged" in n for n in s.notes)
    meta = file_info(tmp_path / "merged.mcap").metadata["lfdfuse"]
    assert meta["cmd_publishers"] == "/teleop,/wall_follow"
    opts = ImportOptions(topics=TopicChoice(cmd_publisher="/wall_follow"))
    kept = import_log(bag, out=tmp_path / "kept.mcap", options=opts)
    assert kept.commands == 8 and kept.cmd_publisher == "/wall_follow"
    assert not any("merged" in n for n in kept.notes)
    assert file_info(tmp_path / "kept.mcap").metadata["lfdfuse"]["cmd_publisher"] == "/wall_follow"
    with pytest.raises(
        SourceError, match=r"no publisher /nobody on /cmd_vel \(publishers: /teleop, /wall_follow\)"
    ):
        import_log(
            bag, out=tmp_path / "x.mcap", options=ImportOptions(topics=TopicChoice(cmd_publisher="/nobody"))
        )
    one = ros1_bag(tmp_path / "one.bag", publishers={"/teleop": [(0.0, 0.3, 0.0)]})
    s1 = import_log(one, out=tmp_path / "one.mcap")
    assert (
        s1.publishers == () and "cmd_publishers" not in file_info(tmp_path / "one.mcap").metadata["lfdfuse"]
    )


def test_rosbag2_has_no_publisher_to_pick(tmp_path: Path) -> None:
    bag = ros2_folder(tmp_path / "b")
    with pytest.raises(SourceError, match="rosbag2 stores no publisher"):
        import_log(
            bag, out=tmp_path / "o.mcap", options=ImportOptions(topics=TopicChoice(cmd_publisher="/x"))
        )


def test_the_real_wall_follower_with_a_keyboard_stop(tmp_path: Path) -> None:
    bag = _real(WALL_TWO_PUBLISHERS)
    from lfdfuse.cli import import_cmd  # noqa: F401  (registers the command)
    from lfdfuse.cli.app import app

    r = CliRunner().invoke(app, ["import", str(bag), "-o", str(tmp_path / "o.mcap")], terminal_width=200)
    assert r.exit_code == 0, r.output
    assert "/wall_follow: 240 messages" in r.output and "/teleop_twist_keyboard: 1 message," in r.output
    assert "merged in time order (keep one with --cmd-publisher NAME)" in r.output
    assert "commands: continuous" in r.output
    r = CliRunner().invoke(
        app,
        ["import", str(bag), "-o", str(tmp_path / "k.mcap"), "--cmd-publisher", "/wall_follow"],
        terminal_width=200,
    )
    assert r.exit_code == 0, r.output
    assert "commands 240 (recorded on /cmd_vel by /wall_follow)" in r.output
    from lfdfuse.cli import inspect  # noqa: F401  (registers the command)

    r = CliRunner().invoke(app, ["inspect", str(bag)], terminal_width=200)
    assert r.exit_code == 0, r.output
    assert "2 publishers on /cmd_vel: /teleop_twist_keyboard (1), /wall_follow (240)" in r.output


# --- ROS 1 frames with a leading slash ------------------------------------------------------------


def test_frames_with_a_leading_slash_find_the_mount(tmp_path: Path) -> None:
    plain = import_log(
        ros1_bag(tmp_path / "a.bag", publishers={"/t": [(0.0, 0.3, 0.0)]}), out=tmp_path / "a.mcap"
    )
    slashed = import_log(
        ros1_bag(tmp_path / "b.bag", publishers={"/t": [(0.0, 0.3, 0.0)]}, slash=True),
        out=tmp_path / "b.mcap",
    )
    for s in (plain, slashed):
        assert math.isclose(s.mount.x_m, -0.1, abs_tol=1e-9) and math.isclose(abs(s.mount.yaw_rad), math.pi)
        assert "unknown" not in s.mount_from
    assert slashed.mount_from == plain.mount_from
