"""Importers: every real log in ../shared/realdata, and tiny hand-made logs with each quirk."""

from __future__ import annotations

import gzip
import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from lfdfuse.errors import ConfigError, LogError
from lfdfuse.log.reader import file_info, read_run
from lfdfuse.robot.mount import Mount, base_geometry
from lfdfuse.robot.records import ScanRecord
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.sources.importers import detect_format, is_lfdfuse_log, require_lfdfuse_log
from lfdfuse.sources.importers.convert import ImportOptions, import_log
from lfdfuse.sources.importers.derive import commands_from_poses
from lfdfuse.sources.importers.goals import parse_goals
from lfdfuse.sources.importers.records import SourceError, TopicChoice, stamp_ns
from tests.conftest import SHARED, mcap_check

REAL = SHARED / "realdata"
TURTLEBOT = REAL / "ros2" / "macfirst_floor_take_2.mcap"
NEATO = REAL / "ros1" / "neato-keyboard-middle.bag"

# log → (format, scans, commands or None when derived, poses)
LOGS = {
    "ros2/macfirst_floor_take_2.mcap": ("ros2", 357, 192, 920),
    "ros2/macfirst_floor_take_2": ("ros2", 357, 192, 920),
    "ros1/neato-keyboard-middle.bag": ("ros1", 185, 6, 278),
    "ros1/demo_stationary_simple_environment.bag": ("ros1", 1265, 0, 0),
    "carmen/mit-csail.clf": ("carmen", 1988, None, 1988),
    "carmen/intel-corrected.log.gz": ("carmen", 910, None, 910),
    "carmen/freiburg-079-corrected.log.gz": ("carmen", 4791, None, 4791),
    "breezyslam/exp2.dat": ("breezyslam", 641, None, 641),
}


def _real(rel: str) -> Path:
    p = REAL / rel
    if not p.exists():
        pytest.skip("shared real data not present (../shared/realdata or $LFDFUSE_SHARED)")
    return p


@pytest.fixture(scope="module")
def imported(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Every real log imported once (skipped without the shared data)."""
    out = tmp_path_factory.mktemp("imported")
    done: dict[str, Path] = {}
    for rel in LOGS:
        src = REAL / rel
        if src.exists():
            done[rel] = out / (src.name.replace(".", "_") + ".mcap")
            import_log(src, out=done[rel])
    return done


@pytest.mark.parametrize("rel", list(LOGS))
def test_every_real_log_imports_with_exact_counts(rel: str, imported: dict[str, Path]) -> None:
    src = _real(rel)
    fmt, scans, cmds, poses = LOGS[rel]
    assert detect_format(src) == fmt
    info = file_info(imported[rel])
    counts = {topic: n for topic, (_s, _e, n) in info.channels.items()}
    assert counts["/scan"] == scans
    assert counts.get("/pose", 0) == poses
    assert counts.get("/cmd_vel", 0) == (poses - 1 if cmds is None else cmds)
    meta = info.metadata["lfdfuse"]
    assert meta["command"] == "import" and meta["format"] == fmt and meta["tool"] == "lfdfuse"
    assert float(meta["laser_max_range_m"]) > 0
    assert is_lfdfuse_log(imported[rel])


def test_mount_and_geometry_of_the_two_teleop_demos(imported: dict[str, Path]) -> None:
    _real("ros1/neato-keyboard-middle.bag")
    tb = read_run(imported["ros2/macfirst_floor_take_2.mcap"])
    # the TurtleBot's lidar is turned +90°: its first beam (−179°) points to −89° on the robot
    assert tb.geometry.count == 720 and math.isclose(
        tb.geometry.start_rad, -3.1241393 + math.pi / 2, abs_tol=1e-6
    )
    assert tb.geometry.max_range_m == 12.0 and (tb.ranges_m <= 12.0).all()
    neato = read_run(imported["ros1/neato-keyboard-middle.bag"])
    # the Neato's lidar is turned by π: beam 0 points straight ahead; its 361st beam is a repeat
    assert neato.geometry.count == 360 and abs(math.sin(neato.geometry.start_rad)) < 1e-5
    assert math.cos(neato.geometry.start_rad) > 0
    meta = neato.metadata
    assert meta["laser_mount"].startswith("-0.1016,0.0,") and meta["v_max_mps"] == "0.3"
    for rel in ("ros2/macfirst_floor_take_2.mcap", "ros2/macfirst_floor_take_2"):
        assert file_info(imported[rel]).metadata["lfdfuse"]["laser_mount_from"].startswith("/tf_static")


def test_real_imports_pass_the_independent_reader(imported: dict[str, Path]) -> None:
    _real("ros1/neato-keyboard-middle.bag")
    for rel in (
        "ros2/macfirst_floor_take_2.mcap",
        "ros1/neato-keyboard-middle.bag",
        "carmen/intel-corrected.log.gz",
    ):
        report = json.loads(mcap_check(imported[rel]))
        assert report["ok"] and report["outOfOrder"] == 0
        assert report["schemas"]["/scan"] == "foxglove.LaserScan"


@pytest.mark.parametrize("rel", ["ros2/macfirst_floor_take_2.mcap", "ros1/neato-keyboard-middle.bag"])
def test_teleop_demos_segment(rel: str, imported: dict[str, Path], tmp_path: Path) -> None:
    _real(rel)
    res = segment_file(imported[rel], out=tmp_path / "seg.mcap")
    assert len(res.t_ns) == LOGS[rel][1]
    assert res.informative.sum() > 0.5 * len(res.t_ns)
    assert "sonar_avoid" in res.names and not any(n.startswith("attract_") for n in res.names)


def test_segment_on_a_foreign_mcap_says_import_first(tmp_path: Path) -> None:
    src = _real("ros2/macfirst_floor_take_2.mcap")
    with pytest.raises(LogError, match="run `lfdfuse import") as err:
        require_lfdfuse_log(src)
    assert "\n" not in str(err.value)
    with pytest.raises(SourceError, match="already an lfdfuse demo"):
        p = tmp_path / "demo.mcap"
        import_log(src, out=p)
        detect_format(p)


def test_goals_become_targets_and_split_the_demo(tmp_path: Path) -> None:
    src = _real("ros2/macfirst_floor_take_2.mcap")
    goals = parse_goals([{"t": 20.0, "name": "hall"}, {"t": 40.0}], origin="test")
    out = tmp_path / "g.mcap"
    s = import_log(src, out=out, options=ImportOptions(goals=goals, teacher="human"))
    assert s.goals == ("goal_hall", "goal_2")
    res = segment_file(out, out=tmp_path / "g.seg.mcap")
    assert "attract_goal_hall" in res.names
    assert [seg.goal for seg in res.segmentation.segments][:2] == ["attract_goal_hall", "attract_goal_2"]


def test_topic_overrides_and_their_errors(tmp_path: Path) -> None:
    src = _real("ros1/neato-keyboard-middle.bag")
    s = import_log(
        src,
        out=tmp_path / "s.mcap",
        options=ImportOptions(topics=TopicChoice(scan="/stable_scan"), cmd_from="odom"),
    )
    assert s.topics["scan"] == "/stable_scan" and s.scans == 184 and s.commands == 277
    assert s.dropped["command: replaced by commands derived from odometry"] == 6
    with pytest.raises(
        SourceError, match=r"no topic /nope \(laser scans: /extrapolated_scan, /scan, /stable_scan\)"
    ):
        import_log(src, out=tmp_path / "x.mcap", options=ImportOptions(topics=TopicChoice(scan="/nope")))
    with pytest.raises(SourceError, match="is not sensor_msgs/LaserScan"):
        import_log(src, out=tmp_path / "x.mcap", options=ImportOptions(topics=TopicChoice(scan="/odom")))
    assert not (tmp_path / "x.mcap").exists()


# --- tiny hand-made logs, one quirk each --------------------------------------------------------


def _carmen_lines() -> list[str]:
    r = " ".join(["1.0"] * 178 + ["81.91", "0.5"])
    return [
        "# CARMEN log",
        "PARAM robot_frontlaser_offset 0.1 nohost 0",
        "PARAM robot_max_t_vel 0.45 nohost 0",
        "PARAM robot_front_laser_max 80.99 nohost 0",
        f"FLASER 180 {r} 0.2 0 0 0.2 0 0 100.200000 host 1",
        "ODOM 0.2 0 0 0 0 0 0 host 0",  # stamped 0
        f"FLASER 180 {r} 0.0 0 0 0.0 0 0 100.000000 host 2",  # out of order
        "NEFF 12",
        f"FLASER 180 {r} 0.4 0 0.1 0.4 0 0.1 100.400000 host 3",
        "FLASER 180 1.0 2.0",  # truncated
    ]


@pytest.mark.parametrize("gz", [False, True])
def test_carmen_quirks(tmp_path: Path, gz: bool) -> None:
    text = "\n".join(_carmen_lines()) + "\n"
    src = tmp_path / ("t.log.gz" if gz else "t.clf")
    src.write_bytes(gzip.compress(text.encode(), mtime=0) if gz else text.encode())
    assert detect_format(src) == "carmen"
    s = import_log(src, out=tmp_path / "o.mcap")
    assert (s.scans, s.commands, s.poses) == (3, 2, 3)
    assert s.dropped == {
        "FLASER: truncated line": 1,
        "NEFF: not a laser, odometry or parameter line": 1,
        "ODOM: time stamp 0": 1,
    }
    assert "1 FLASER lines out of time order (sorted)" in s.notes
    assert s.v_max_mps == 0.45 and s.limits_from.startswith("log parameters")
    assert s.mount == Mount(0.1, 0.0, 0.0) and s.geometry.max_range_m == 80.99
    run = read_run(tmp_path / "o.mcap")
    assert run.t_ns.tolist() == [100_000_000_000, 100_200_000_000, 100_400_000_000]
    assert run.ranges_m[0, 178] == 80.99 and run.ranges_m[0, 179] == 0.5  # sentinel = no return
    assert run.geometry.start_rad == -math.pi / 2 and math.isclose(run.geometry.increment_rad, math.pi / 180)
    assert np.allclose(run.cmd_v_mps, 1.0, atol=0.01)  # 0.2 m per 0.2 s, straight ahead


def test_breezyslam_quirks(tmp_path: Path) -> None:
    rows = []
    for k, t_us in enumerate([1_000_000, 1_100_000, 1_200_000]):
        ticks = 1000 * k  # both wheels: 1000 ticks = half a turn = 0.2419 m per 0.1 s
        ranges = ["0", "5700", *["1500"] * 680]  # 0 and beyond 5.6 m: no return
        rows.append(" ".join([str(t_us), "0", str(ticks), str(ticks), *["7"] * 20, *ranges, "45"]))
    src = tmp_path / "exp.dat"
    src.write_text("\n".join(rows) + "\n")
    assert detect_format(src) == "breezyslam"
    s = import_log(src, out=tmp_path / "o.mcap")
    assert (s.scans, s.commands, s.poses) == (3, 2, 3) and s.geometry.count == 682
    run = read_run(tmp_path / "o.mcap")
    assert run.ranges_m[0, :3].tolist() == [5.6, 5.6, 1.5]
    assert math.isclose(run.geometry.start_rad, -math.radians(120))
    assert np.allclose(run.cmd_v_mps, math.pi * 0.077 / 0.1, atol=1e-5) and np.allclose(
        run.cmd_omega_rps, 0.0
    )


def _ros2_bag(path: Path, *, flipped: bool) -> None:
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    hdr = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id="laser")
    q = (1.0, 0.0, 0.0, 0.0) if flipped else (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))
    tf = T["geometry_msgs/msg/TransformStamped"](
        header=T["std_msgs/msg/Header"](stamp=hdr.stamp, frame_id="base_link"),
        child_frame_id="laser",
        transform=T["geometry_msgs/msg/Transform"](
            translation=T["geometry_msgs/msg/Vector3"](x=0.1, y=0.0, z=0.2),
            rotation=T["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]),
        ),
    )
    ranges = np.array([1.0, np.inf, np.nan, 0.0, 13.0, 0.1, 2.0, 3.0], dtype=np.float32)
    with Writer(path, version=8) as w:
        c_tf = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        c_scan = w.add_connection("/base_scan", "sensor_msgs/msg/LaserScan", typestore=ts)
        c_cmd = w.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=ts)
        w.write(
            c_tf, 1, ts.serialize_cdr(T["tf2_msgs/msg/TFMessage"](transforms=[tf]), "tf2_msgs/msg/TFMessage")
        )
        for k in range(3):
            scan = T["sensor_msgs/msg/LaserScan"](
                header=hdr, angle_min=-math.pi / 4, angle_max=math.pi / 4 * 3, angle_increment=math.pi / 8,
                time_increment=0.0, scan_time=0.1, range_min=0.15, range_max=12.0, ranges=ranges,
                intensities=np.zeros(0, dtype=np.float32),
            )  # fmt: skip
            t = 1_700_000_000_123_456_789 + k * 100_000_000  # an epoch stamp, exact to the ns
            w.write(c_scan, t, ts.serialize_cdr(scan, "sensor_msgs/msg/LaserScan"))
            twist = T["geometry_msgs/msg/Twist"](
                linear=T["geometry_msgs/msg/Vector3"](x=0.3, y=0.0, z=0.0),
                angular=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.1 * k),
            )
            w.write(c_cmd, t + 1, ts.serialize_cdr(twist, "geometry_msgs/msg/Twist"))


@pytest.mark.parametrize("flipped", [False, True])
def test_ros2_quirks(tmp_path: Path, flipped: bool) -> None:
    bag = tmp_path / "bag"
    _ros2_bag(bag, flipped=flipped)
    assert detect_format(bag) == "ros2"
    s = import_log(bag, out=tmp_path / "o.mcap")
    assert s.topics == {"scan": "/base_scan", "cmd": "/cmd_vel"}  # picked by type
    assert (s.scans, s.commands, s.poses) == (3, 3, 0) and s.v_max_mps == 0.3
    run = read_run(tmp_path / "o.mcap")
    assert run.t_ns[0] == 1_700_000_000_123_456_789 and run.cmd_t_ns[0] == 1_700_000_000_123_456_790
    r = run.ranges_m[0].tolist()
    if flipped:  # upside down: bearing = −sensor angle, so the beams are reversed
        assert r == [3.0, 2.0, 12.0, 12.0, 12.0, 12.0, 12.0, 1.0]
        assert math.isclose(run.geometry.start_rad, -math.pi * 5 / 8, abs_tol=1e-6)  # −(last beam)
    else:  # inf, NaN, 0, beyond range_max and below range_min: all no return
        assert r == [1.0, 12.0, 12.0, 12.0, 12.0, 12.0, 2.0, 3.0]
        assert math.isclose(run.geometry.start_rad, math.pi / 4, abs_tol=1e-6)  # −45° + 90°


def test_base_geometry_drops_a_repeated_closing_beam() -> None:
    rec = ScanRecord(0, -math.pi, math.pi / 180, np.ones(361), 5.0)
    geom, reverse, closing = base_geometry(rec, Mount(-0.1, 0.0, math.pi))
    assert closing and not reverse and geom.count == 360 and abs(geom.start_rad) < 1e-12


def test_derived_commands_turn_and_drive() -> None:
    t = np.arange(5, dtype=np.int64) * 500_000_000 + 1_600_000_000_000_000_000
    th = np.array([0.0, 0.1, 0.2, 0.3, 0.4])
    x = np.cumsum([0.0, 0.1, 0.1, 0.1, 0.1]) * np.cos(th)
    y = np.cumsum([0.0, 0.1, 0.1, 0.1, 0.1]) * np.sin(th)
    ct, v, w = commands_from_poses(t, x, y, th)
    assert ct.tolist() == t[:-1].tolist() and np.allclose(w, 0.2) and np.all(v > 0)
    assert commands_from_poses(t[:1], x[:1], y[:1], th[:1])[0].shape == (0,)


def test_stamps_and_goal_files() -> None:
    assert stamp_ns("1663967375.548411329") == 1_663_967_375_548_411_329
    assert stamp_ns("0.000246") == 246_000
    assert parse_goals([3, {"x": 1, "y": 2, "name": "door"}], origin="g")[1].name == "door"
    for bad in ([], [{"t": -1}], [{"x": 1}], [{"t": 1, "radius": 2}], [{"t": 1}, {"t": 2, "name": "1"}]):
        with pytest.raises(ConfigError):
            parse_goals(bad, origin="g")


def test_unknown_and_missing_sources(tmp_path: Path) -> None:
    (tmp_path / "x.txt").write_text("hello\n")
    with pytest.raises(SourceError, match="not a log format lfdfuse can import"):
        import_log(tmp_path / "x.txt", out=tmp_path / "o.mcap")
    with pytest.raises(SourceError, match="no such file"):
        import_log(tmp_path / "nope.bag", out=tmp_path / "o.mcap")
    assert sorted(os.listdir(tmp_path)) == ["x.txt"]


# --- the command line ---------------------------------------------------------------------------


def test_cli_import_prints_every_count(tmp_path: Path) -> None:
    from lfdfuse.cli import import_cmd, segment  # noqa: F401  (registers the commands)
    from lfdfuse.cli.app import app

    src = tmp_path / "t.clf"
    src.write_text("\n".join(_carmen_lines()) + "\n")
    res = CliRunner().invoke(app, ["import", str(src), "-o", str(tmp_path / "o.mcap")], terminal_width=200)
    assert res.exit_code == 0, res.output
    assert "scans 3, commands 2 (derived from odometry: FLASER pose), poses 3" in res.output
    assert "topics: scan FLASER (picked), odom FLASER pose (picked)" in res.output
    assert "1  ODOM: time stamp 0" in res.output
    bad = CliRunner().invoke(app, ["import", str(tmp_path / "nope.bag"), "-o", str(tmp_path / "x.mcap")])
    assert bad.exit_code == 1 and bad.stderr.strip().startswith("error: no such file")


def test_installed_command_end_to_end(tmp_path: Path) -> None:
    src = _real("ros1/neato-keyboard-middle.bag")
    exe = shutil.which("lfdfuse", path=str(Path(sys.executable).parent))
    if exe is None:
        pytest.skip("the lfdfuse command is not installed")
    env = {**os.environ, "COLUMNS": "200"}
    res = subprocess.run(
        [exe, "import", str(src), "--teacher", "human", "-o", "neato.mcap"],
        cwd=tmp_path, capture_output=True, text=True, env=env, timeout=120,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert "scans 185, commands 6 (recorded on /cmd_vel), poses 278" in res.stdout
    assert "yaw=-180.0°" in res.stdout and "repeats the first bearing" in res.stdout
    seg = subprocess.run(
        [exe, "segment", "neato.mcap"], cwd=tmp_path, capture_output=True, text=True, timeout=120
    )
    assert seg.returncode == 0, seg.stderr
    foreign = subprocess.run([exe, "segment", str(TURTLEBOT)], cwd=tmp_path, capture_output=True, text=True)
    if foreign.returncode == 1 and "lfdfuse import" in foreign.stderr:  # once segment checks its input
        assert foreign.stderr.count("\n") == 1


def test_robot_limits_ignore_a_wild_command_and_say_so() -> None:
    """One wild command among a Neato's commands must not set its v_max (it would read 19.9 m/s)."""
    import numpy as np

    from lfdfuse.sources.importers.convert import ImportOptions, _limits

    rng = np.random.default_rng(0)
    v = np.concatenate([np.full(40, 0.3), np.zeros(20), [19.9]])
    w = rng.choice([0.0, 0.3, -0.3], len(v))
    odom = (np.abs(rng.normal(0.25, 0.03, 200)), rng.normal(0.0, 0.2, 200))
    notes: list[str] = []
    v_max, w_max, _ = _limits(ImportOptions(), None, None, v, w, False, odom=odom, notes=notes)
    assert v_max == 0.3 and w_max == 0.3
    assert len(notes) == 1 and notes[0].startswith("warning: implausible command speed up to 19.9 m/s")
    # continuous commands (a scripted or planner log): a high percentile, not the maximum
    notes.clear()
    v = np.concatenate([rng.uniform(0.0, 0.5, 500), [7.0]])
    v_max, _, _ = _limits(ImportOptions(), None, None, v, rng.uniform(-1, 1, len(v)), False, notes=notes)
    assert v_max is not None and 0.45 < v_max <= 0.5 and notes and "7" in notes[0]
