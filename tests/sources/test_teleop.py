"""``lfdfuse teleop``: the pure key and message mapping, the session, and the real thing.

The real thing: the installed command in a pseudo-terminal (keys, Ctrl-C, SIGTERM), the
Foxglove server with a WebSocket client speaking the protocol, and a three-goal task taught
by scripted input that segments by goals and is learned well enough to complete.
"""

from __future__ import annotations

import asyncio
import fcntl
import json
import math
import os
import pty
import re
import select
import shutil
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import orjson
import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.control.command import DriveParams
from lfdfuse.errors import ConfigError
from lfdfuse.log.reader import file_info, iter_messages
from lfdfuse.log.schemas import schema
from lfdfuse.robot.pose import Pose
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sources.teleop.clock import SimClock
from lfdfuse.sources.teleop.inputs import Input, TwistError, decode_teleop_input, parse_twist
from lfdfuse.sources.teleop.keys import MOVES, KeyDecoder, KeyState, press
from lfdfuse.sources.teleop.script import (
    ScriptInput,
    key_entry,
    load_script,
    parse_csv,
    parse_yaml,
    twist_entry,
    write_csv,
)
from lfdfuse.sources.teleop.session import (
    TeleopOptions,
    TeleopSession,
    make_session,
    stop_on_signals,
    teleop,
)
from lfdfuse.sources.teleop.view import ARROWS, render_map
from lfdfuse.world.model import load_world
from tests.conftest import ROOT, mcap_check

EXE = shutil.which("lfdfuse", path=str(Path(sys.executable).parent)) or shutil.which("lfdfuse")
runner = CliRunner()


# -- keys: teleop_twist_keyboard semantics ------------------------------------------------------


@pytest.mark.parametrize(
    ("key", "sign"),
    [
        ("i", (1, 0)),
        (",", (-1, 0)),
        ("j", (0, 1)),
        ("l", (0, -1)),
        ("u", (1, 1)),
        ("o", (1, -1)),
        ("m", (-1, -1)),
        (".", (-1, 1)),
        ("up", (1, 0)),
        ("down", (-1, 0)),
        ("left", (0, 1)),
        ("right", (0, -1)),
    ],
)
def test_move_keys_set_a_direction_that_holds(key: str, sign: tuple[int, int]) -> None:
    s = press(KeyState(speed_mps=0.3, turn_rps=0.8), key).state
    assert s.command == pytest.approx((0.3 * sign[0], 0.8 * sign[1]))
    assert press(s, "k").state.command == (0.0, 0.0)
    assert press(s, "space").state.command == (0.0, 0.0)


def test_speed_keys_scale_within_the_robot_limits() -> None:
    lim = DriveParams()
    s = press(KeyState(speed_mps=0.2, turn_rps=1.0), "i").state
    s = press(s, "q").state
    assert s.command == pytest.approx((0.22, 0.0)) and s.turn_rps == pytest.approx(1.1)
    s = press(s, "z").state
    assert s.speed_mps == pytest.approx(0.198)
    for _ in range(50):
        s = press(s, "q", lim).state
    assert s.speed_mps == lim.v_max_mps and s.turn_rps == lim.omega_max_rps
    assert s.command == (lim.v_max_mps, 0.0)  # the held direction keeps its new speed
    for _ in range(200):
        s = press(s, "z", lim).state
    assert s.speed_mps > 0 and s.turn_rps > 0
    w = press(KeyState(speed_mps=0.2, turn_rps=1.0), "w").state
    e = press(KeyState(speed_mps=0.2, turn_rps=1.0), "e").state
    assert (w.speed_mps, w.turn_rps) == (pytest.approx(0.22), 1.0)
    assert (e.speed_mps, e.turn_rps) == (0.2, pytest.approx(1.1))


def test_esc_and_ctrl_c_quit_and_other_keys_stop() -> None:
    moving = press(KeyState(), "i").state
    for key in ("esc", "ctrl-c"):
        eff = press(moving, key)
        assert eff.quit and eff.state.command == (0.0, 0.0)
    eff = press(moving, "h")
    assert not eff.quit and not eff.known and eff.state.command == (0.0, 0.0)
    assert set(MOVES) >= {"i", ",", "j", "l", "u", "o", "m", "."}


def test_decoder_turns_terminal_bytes_into_keys() -> None:
    d = KeyDecoder()
    assert d.feed(b"i,\x1b[A\x1b[B\x1b[C\x1b[D \x03") == [
        "i",
        ",",
        "up",
        "down",
        "right",
        "left",
        "space",
        "ctrl-c",
    ]
    assert d.feed(b"\x1bOA") == ["up"]  # application cursor mode
    assert d.feed(b"\x1b[1;5C") == ["right"]  # ctrl-right: a sequence, not Esc + keys
    assert d.feed(b"\x1b[15~") == ["unknown"]  # F5
    assert d.feed(b"\x1bi") == ["esc", "i"]


def test_decoder_waits_for_a_split_escape_sequence_and_flushes_a_lone_esc() -> None:
    d = KeyDecoder()
    assert d.feed(b"i\x1b") == ["i"]
    assert d.feed(b"[") == []
    assert d.feed(b"D") == ["left"]
    assert d.flush() == []
    assert d.feed(b"\x1b") == []
    assert d.flush() == ["esc"]
    assert d.feed(b"\x1b[") == [] and d.flush() == ["esc"]  # a cut-off sequence


# -- client messages ------------------------------------------------------------------------------


def test_parse_twist_reads_the_teleop_panel_message() -> None:
    panel = {"linear": {"x": 1, "y": 0, "z": 0}, "angular": {"x": 0, "y": 0, "z": -1}}
    assert parse_twist(json.dumps(panel).encode()) == (1.0, -1.0)
    assert parse_twist('{"angular": {"z": 0.5}}') == (0.0, 0.5)
    assert parse_twist('{"twist": {"linear": {"x": 0.2}}}') == (0.2, 0.0)


@pytest.mark.parametrize(
    "payload",
    [b"", b"not json", b"[1, 2]", b'{"linear": 3}', b'{"linear": {"x": "fast"}}', b'{"linear": {"x": NaN}}'],
)
def test_parse_twist_rejects_garbage(payload: bytes) -> None:
    with pytest.raises(TwistError):
        parse_twist(payload)


# -- scripts -------------------------------------------------------------------------------------


def test_scripts_in_yaml_and_csv(tmp_path: Path) -> None:
    entries = parse_yaml([{"t": 1.0, "key": "i"}, {"t": 0.5, "twist": [0.3, 0.1]}, {"t": 2, "end": True}])
    src = ScriptInput(entries)
    assert [i.kind for i in src.poll(0.4)] == []
    assert [(i.kind, i.text) for i in src.poll(1.0)][1] == ("key", "i")
    assert [i.kind for i in src.poll(5.0)] == ["end"]
    csv_entries = parse_csv(write_csv(entries[:2]))
    assert [(e.t_ns, e.input.kind) for e in csv_entries] == [(e.t_ns, e.input.kind) for e in entries[:2]]
    assert parse_twist(csv_entries[1].input.text) == (0.3, 0.1)
    p = tmp_path / "s.csv"
    p.write_text("t,v,w\n0,0.4,0\n1.5,0,0\n")
    assert [e.t_ns for e in load_script(p)] == [0, 1_500_000_000]
    # a script without an end ends with its last entry
    assert [i.kind for i in ScriptInput(load_script(p)).poll(9.0)] == ["message", "message", "end"]


@pytest.mark.parametrize(
    ("data", "needle"),
    [
        ([], "non-empty list"),
        ([{"key": "i"}], "entry 1: needs a time"),
        ([{"t": 0, "key": "i", "twist": [0, 0]}], "exactly one"),
        ([{"t": -1, "key": "i"}], "between 0"),
        ([{"t": 0, "twist": [0]}], "twist must be"),
        ([{"t": 0, "speed": 1}], "unknown key 'speed'"),
        ([{"t": 0, "twist": ["a", 0]}], "must be a number"),
        ([{"t": 0, "key": "foo"}], "entry 1: key 'foo' is not a key name"),
        ([{"t": 0, "key": "i"}, {"t": 1, "key": "upp"}], "entry 2: key 'upp'"),
    ],
)
def test_bad_scripts_name_the_entry(data: Any, needle: str) -> None:
    with pytest.raises(ConfigError, match=needle):
        parse_yaml(data)


# -- the session ---------------------------------------------------------------------------------


class Fed:
    """An input source fed by hand: ``at[t_s]`` lists the inputs arriving at that time."""

    def __init__(self, at: dict[float, Sequence[Input]]) -> None:
        self.at = dict(at)

    def poll(self, t_s: float) -> list[Input]:
        due = [t for t in self.at if t <= t_s + 1e-9]
        return [i for t in sorted(due) for i in self.at.pop(t)]


def _run(
    tmp_path: Path, inputs: dict[float, Sequence[Input]], **kw: Any
) -> tuple[Any, TeleopSession, list[tuple[float, float]], list[Any]]:
    opts = TeleopOptions(world=load_world("building"), input_name="test", **kw)
    session = make_session(opts, inputs=[Fed(inputs)], clock=SimClock())
    out = tmp_path / "t.mcap"
    summary = teleop(opts, session=session, out=out)
    cmds = [
        (m["linear"]["x"], m["angular"]["z"])
        for _, _, _, d in iter_messages(out, topics=["/cmd_vel"])
        for m in [orjson.loads(d)]
    ]
    recs = [
        decode_teleop_input(orjson.loads(d)) for _, _, _, d in iter_messages(out, topics=["/teleop/input"])
    ]
    return summary, session, cmds, recs


def key(k: str) -> list[Input]:
    return [Input("key", k, "keyboard")]


def twist(v: float, w: float) -> list[Input]:
    return [
        Input(
            "message", json.dumps({"linear": {"x": v}, "angular": {"z": w}}), "client", "geometry_msgs/Twist"
        )
    ]


@pytest.mark.skipif(
    threading.current_thread() is not threading.main_thread(), reason="signals need the main thread"
)
@pytest.mark.parametrize("after_s", [0.05, 0.13, 0.21, 0.34, 0.47])
def test_a_signal_during_the_wall_clock_wait_ends_the_run_at_the_next_period(
    tmp_path: Path, after_s: float
) -> None:
    """Real SIGINTs through :func:`stop_on_signals` while a real-time run paces itself: the run
    ends with the signal's name within a period or two and saves its log. (A handler that
    set a ``threading.Event`` whose own lock the waiting loop could hold would hang on Ctrl-C, rarely.)"""
    opts = TeleopOptions(world=load_world("building"), input_name="test")
    session = make_session(opts, inputs=[Fed({0.0: key("i")})])  # the wall clock
    main, sent = threading.get_ident(), []

    def interrupt() -> None:
        time.sleep(after_s)
        while not session.end_reason:  # until it is seen: a burst, as a held Ctrl-C gives
            sent.append(time.monotonic())
            signal.pthread_kill(main, signal.SIGINT)
            time.sleep(0.002)

    th, before = threading.Thread(target=interrupt, daemon=True), signal.getsignal(signal.SIGINT)
    with stop_on_signals(session):
        th.start()
        summary = teleop(opts, session=session, out=tmp_path / "t.mcap")
        ended_at = time.monotonic()
    th.join(5)
    assert summary.ended == "signal SIGINT"
    assert sent and ended_at - sent[0] < 3 * opts.robot.dt_s + 0.5  # a period or two, and a loaded machine
    assert (tmp_path / "t.mcap").exists() and signal.getsignal(signal.SIGINT) is before


def test_a_key_command_holds_until_the_next_and_the_run_ends_on_esc(tmp_path: Path) -> None:
    summary, _, cmds, recs = _run(tmp_path, {0.0: key("i"), 1.0: key("j"), 1.5: key("k"), 2.0: key("esc")})
    assert summary.ended == "key esc"
    assert cmds[:10] == [(0.4, 0.0)] * 10
    assert cmds[10:15] == [(0.0, 1.0)] * 5
    assert cmds[15:] == [(0.0, 0.0)] * 6
    assert [(r.input, r.effect) for r in recs] == [
        ("i", "move"),
        ("j", "move"),
        ("k", "stop"),
        ("esc", "end"),
    ]
    assert summary.run.distance_m == pytest.approx(0.4, abs=0.01)


def test_client_commands_are_clipped_and_time_out(tmp_path: Path) -> None:
    # a client repeating once a second holds its command; silence for longer than the
    # timeout stops the robot; garbage is recorded as invalid and changes nothing
    inputs = {float(t): twist(1.0, -9.0) for t in range(4)}
    inputs[5.0] = [Input("message", "nonsense", "client", "geometry_msgs/Twist")]
    summary, _, cmds, recs = _run(tmp_path, inputs, twist_timeout_s=2.5, duration_s=9.0)
    lim = DriveParams()
    assert cmds[5] == (lim.v_max_mps, -lim.omega_max_rps)
    moving = [i for i, c in enumerate(cmds) if c != (0.0, 0.0)]
    assert moving[0] == 0 and 3.0 + 2.5 < (moving[-1] + 1) * 0.1 < 3.0 + 2.65  # held 2.5 s after the last
    assert summary.ended == "duration" and len(cmds) == 91
    effects = [r.effect for r in recs]
    assert "timeout" in effects and any(e.startswith("invalid") for e in effects)


def test_a_fast_client_times_out_sooner(tmp_path: Path) -> None:
    inputs = {round(0.2 * k, 1): twist(0.3, 0.0) for k in range(11)}  # 5 Hz for 2 s
    _, _, cmds, _ = _run(tmp_path, inputs, twist_timeout_s=2.5, duration_s=5.0)
    last = max(i for i, c in enumerate(cmds) if c != (0.0, 0.0))
    assert 2.0 + 0.5 <= (last + 1) * 0.1 <= 2.0 + 0.8


def test_stop_from_another_thread_ends_the_run_and_saves(tmp_path: Path) -> None:
    opts = TeleopOptions(world=load_world("corridor"), input_name="test")
    session = make_session(opts, inputs=[Fed({0.0: key("i")})])  # real time
    threading.Timer(0.5, session.stop, args=("signal SIGTERM",)).start()
    t0 = time.monotonic()
    summary = teleop(opts, session=session, out=tmp_path / "s.mcap")
    assert 0.4 < time.monotonic() - t0 < 2.0  # paced at 10 Hz, ended promptly
    assert summary.ended == "signal SIGTERM"
    meta = file_info(tmp_path / "s.mcap").metadata["lfdfuse"]
    assert meta["teacher"] == "human" and meta["ended"] == "signal SIGTERM" and meta["command"] == "teleop"


def test_an_exception_leaves_no_file(tmp_path: Path) -> None:
    class Broken:
        def poll(self, t_s: float) -> list[Input]:
            if t_s > 0.5:
                raise RuntimeError("boom")
            return []

    opts = TeleopOptions(world=load_world("corridor"), input_name="test")
    session = make_session(opts, inputs=[Broken()], clock=SimClock())
    with pytest.raises(RuntimeError):
        teleop(opts, session=session, out=tmp_path / "x.mcap")
    assert list(tmp_path.iterdir()) == []


def test_goals_are_detected_live(tmp_path: Path) -> None:
    world = load_world("building")
    red = world.target("red")
    start = Pose(red.x, red.y - 2.0, math.pi / 2)  # up the corridor, facing red
    summary, session, _, _ = _run(tmp_path, {0.0: key("i"), 6.0: key("esc")}, start=start)
    assert [n for n, _ in session.reached] == ["red"]
    assert summary.run.reached[0][1] == pytest.approx(3.2, abs=0.3)  # 1.25 m at 0.4 m/s: within 0.75 m


def test_the_input_message_matches_its_schema(tmp_path: Path) -> None:
    import jsonschema

    _, _, _, _ = _run(tmp_path, {0.0: key("u"), 0.5: twist(0.1, 0.2), 1.0: key("esc")})
    for _, name, _, data in iter_messages(tmp_path / "t.mcap", topics=["/teleop/input"]):
        jsonschema.validate(orjson.loads(data), schema(name))
    assert (ROOT / "schemas" / "lfdfuse.TeleopInput.json").read_bytes() == (
        ROOT / "lfdfuse" / "schemas" / "lfdfuse.TeleopInput.json"
    ).read_bytes()


def test_view_draws_walls_targets_laser_and_the_robot() -> None:
    world = load_world("building")
    geom = SensorParams().laser.geometry
    pose = Pose(4.0, 1.2, math.pi / 2)
    ranges = np.full(geom.count, 1.0)
    lines = render_map(world, pose, ranges, geom, cols=60, rows=20)
    assert len(lines) == 20 and all(len(line) == 60 for line in lines)
    text = "\n".join(lines)
    assert "#" in text and "*" in text and text.count(ARROWS[2]) == 1  # ↑: heading +90°
    whole = render_map(world, pose, ranges, geom, cols=170, rows=50)
    assert {"R", "G", "B"} <= set("".join(whole))


def test_layout_file_has_a_3d_panel_on_map_and_a_teleop_panel() -> None:
    layout = json.loads((ROOT / "lfdfuse" / "foxglove" / "teleop-layout.json").read_text())
    panels = layout["configById"]
    three_d = next(v for k, v in panels.items() if k.startswith("3D!"))
    teleop_panel = next(v for k, v in panels.items() if k.startswith("Teleop!"))
    assert three_d["followTf"] == "map" and {"/scan", "/world"} <= set(three_d["topics"])
    assert teleop_panel["topic"] == "/cmd_vel"
    ids = json.dumps(layout["layout"])
    assert all(k in ids for k in panels)


# -- the real command: keyboard through a pseudo-terminal ----------------------------------------


class Pty:
    """The installed ``lfdfuse`` in a pseudo-terminal of ``rows × cols``."""

    def __init__(self, args: list[str], rows: int = 40, cols: int = 120) -> None:
        if EXE is None:
            pytest.skip("the lfdfuse command is not installed")
        self.pid, self.fd = pty.fork()
        if self.pid == 0:  # the child: become the command
            os.environ["TERM"] = "xterm-256color"
            os.execv(EXE, ["lfdfuse", *args])
        fcntl.ioctl(self.fd, termios.TIOCSWINSZ, struct.pack("HHHH", rows, cols, 0, 0))
        self.out = b""
        self.code: int | None = None

    def pump(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if select.select([self.fd], [], [], 0.05)[0]:
                try:
                    self.out += os.read(self.fd, 65536)
                except OSError:
                    return

    def wait_for(self, needle: bytes, timeout: float = 20.0) -> None:
        end = time.monotonic() + timeout
        while needle not in self.out and time.monotonic() < end:
            self.pump(0.1)
        assert needle in self.out, self.out[-2000:]

    def send(self, data: bytes, then: float) -> None:
        os.write(self.fd, data)
        self.pump(then)

    def finish(self, timeout: float = 30.0) -> int:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.pump(0.1)
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid:
                self.code = os.waitstatus_to_exitcode(status)
                self.pump(0.2)
                return self.code
        os.kill(self.pid, signal.SIGKILL)
        raise AssertionError("teleop did not end")

    def echo_on(self) -> bool:
        return bool(termios.tcgetattr(self.fd)[3] & termios.ECHO)

    def text(self) -> str:
        return re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", self.out.decode("utf-8", "replace"))


def _poses(path: Path) -> np.ndarray:
    return np.array(
        [
            (m["pose"]["position"]["x"], m["pose"]["position"]["y"])
            for _, _, _, d in iter_messages(path, topics=["/pose"])
            for m in [orjson.loads(d)]
        ]
    )


def _inputs(path: Path) -> list[Any]:
    return [
        decode_teleop_input(orjson.loads(d)) for _, _, _, d in iter_messages(path, topics=["/teleop/input"])
    ]


def test_keyboard_in_a_terminal_drives_and_ctrl_c_saves(tmp_path: Path) -> None:
    out = tmp_path / "keys.mcap"
    term = Pty(["teleop", "--world", "building", "-o", str(out)])
    term.wait_for("lfdfuse teleop — building".encode())
    frames0, t0 = term.out.count(b"lfdfuse teleop"), time.monotonic()
    term.send(b"i", 2.0)
    term.send(b"\x1b[D", 1.0)  # left arrow: turn in place
    term.send(b"u", 1.0)
    term.send(b"q", 0.5)
    frames = term.out.count(b"lfdfuse teleop") - frames0
    rate = frames / (time.monotonic() - t0)
    term.send(b"\x03", 0.0)  # Ctrl-C: in raw mode the byte, not a signal
    assert term.finish() == 0, term.text()[-3000:]
    assert term.echo_on()  # the terminal is restored
    assert rate >= 5, f"live view refreshed {rate:.1f} times a second"
    text = term.text()
    assert "ended      key ctrl-c" in text and "goals" in text
    report = json.loads(mcap_check(out))
    assert report["ok"] and report["outOfOrder"] == 0
    assert report["schemas"]["/teleop/input"] == "lfdfuse.TeleopInput"
    xy = _poses(out)
    assert np.hypot(*np.diff(xy, axis=0).T).sum() > 1.0  # it moved: 2 s forward, an arc
    assert [r.input for r in _inputs(out)] == ["i", "left", "u", "q", "ctrl-c"]
    seg = runner.invoke(app, ["segment", str(out)])
    assert seg.exit_code == 0, seg.output


def test_sigterm_ends_a_keyboard_run_saves_it_and_restores_the_terminal(tmp_path: Path) -> None:
    out = tmp_path / "term.mcap"
    term = Pty(["teleop", "--world", "corridor", "-o", str(out)])
    term.wait_for(b"lfdfuse teleop")
    term.send(b"i", 1.0)
    assert not term.echo_on()  # raw input mode while driving
    os.kill(term.pid, signal.SIGTERM)
    assert term.finish() == 0, term.text()[-3000:]
    assert term.echo_on()
    assert file_info(out).metadata["lfdfuse"]["ended"] == "signal SIGTERM"
    assert not [p for p in tmp_path.iterdir() if p.name != out.name]  # no temp file left


def test_raw_input_mode_is_undone_when_the_run_raises() -> None:
    from lfdfuse.cli.teleop import raw_input_mode

    master, slave = pty.openpty()
    try:
        before = termios.tcgetattr(slave)
        with pytest.raises(RuntimeError), raw_input_mode(slave):
            lflag = termios.tcgetattr(slave)[3]
            assert not lflag & (termios.ECHO | termios.ICANON | termios.ISIG)
            assert termios.tcgetattr(slave)[1] & termios.OPOST  # output stays cooked for rich
            raise RuntimeError("a bug in the loop")
        assert termios.tcgetattr(slave) == before
    finally:
        os.close(master)
        os.close(slave)


def test_keyboard_needs_a_terminal(tmp_path: Path) -> None:
    res = runner.invoke(app, ["teleop", "-o", str(tmp_path / "never.mcap")])
    assert res.exit_code == 1 and "needs a terminal" in res.output
    assert list(tmp_path.iterdir()) == []


# -- the real command: Foxglove server and a protocol client -------------------------------------


async def _drive_over_foxglove(url: str, *, drive_s: float, listen_s: float) -> dict[str, Any]:
    """Speak the Foxglove WebSocket protocol as the Teleop panel does; count /scan messages."""
    import websockets

    async with websockets.connect(url, subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"]) as ws:
        info = json.loads(await ws.recv())
        channels: dict[str, dict[str, Any]] = {}
        while not {"/scan", "/world", "/pose"} <= set(channels):
            m = json.loads(await ws.recv())
            if m["op"] == "advertise":
                channels.update({c["topic"]: c for c in m["channels"]})
        await ws.send(
            json.dumps(
                {"op": "subscribe", "subscriptions": [{"id": 1, "channelId": channels["/scan"]["id"]}]}
            )
        )
        await ws.send(
            json.dumps(
                {
                    "op": "advertise",
                    "channels": [
                        {
                            "id": 7,
                            "topic": "/cmd_vel",
                            "encoding": "json",
                            "schemaName": "geometry_msgs/Twist",
                        }
                    ],
                }
            )
        )
        twist = {"linear": {"x": 0.4, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
        frame = b"\x01" + struct.pack("<I", 7) + json.dumps(twist).encode()
        scans: list[float] = []
        t0 = time.monotonic()
        next_send = t0
        while time.monotonic() - t0 < listen_s:
            if time.monotonic() >= next_send and time.monotonic() - t0 < drive_s:
                await ws.send(frame)  # 1 Hz, the Teleop panel's default rate
                next_send += 1.0
            try:
                m = await asyncio.wait_for(ws.recv(), 0.1)
            except TimeoutError:
                continue
            if isinstance(m, bytes) and m[0] == 0x01 and struct.unpack("<I", m[1:5])[0] == 1:
                scan = json.loads(m[13:])
                assert len(scan["ranges"]) == 181
                scans.append(time.monotonic())
        return {"info": info, "channels": channels, "scans": scans}


def test_a_foxglove_client_drives_and_receives_live_scans(tmp_path: Path) -> None:
    if EXE is None:
        pytest.skip("the lfdfuse command is not installed")
    out = tmp_path / "fox.mcap"
    proc = subprocess.Popen(
        [EXE, "teleop", "--input", "foxglove", "--port", "0", "--world", "building", "-o", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        # read the whole banner through the text buffer: communicate() reads the pipe beneath
        # it, so lines already buffered here would be lost to it
        head, url = "", ""
        while "layout:" not in head:
            line = proc.stdout.readline()
            assert line, proc.stderr.read() if proc.stderr else ""
            head += line
            m = re.search(r"ws://[\d.]+:\d+", line)
            url = url or (m.group(0) if m else "")
        res = asyncio.run(_drive_over_foxglove(url, drive_s=3.0, listen_s=4.0))
        proc.send_signal(signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=30)
        stdout = head + stdout
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, stderr
    assert "clientPublish" in res["info"]["capabilities"] and "json" in res["info"]["supportedEncodings"]
    assert res["channels"]["/scan"]["schemaName"] == "foxglove.LaserScan"
    assert res["channels"]["/world"]["schemaName"] == "foxglove.SceneUpdate"
    scans = res["scans"]
    rate = (len(scans) - 1) / (scans[-1] - scans[0])
    assert rate >= 5, f"{rate:.1f} scans/s"
    assert "app.foxglove.dev" in stdout and "teleop-layout.json" in stdout
    report = json.loads(mcap_check(out))
    assert report["ok"] and report["outOfOrder"] == 0
    xy = _poses(out)
    assert np.hypot(*(xy[-1] - xy[0])) > 0.8  # ≥ 3 s at 0.4 m/s, less the corner
    recs = _inputs(out)
    assert [r.effect for r in recs if r.kind == "message"][:3] == ["move"] * 3
    assert recs[0].source.startswith("foxglove client")
    assert file_info(out).metadata["lfdfuse"]["input"] == "foxglove"


def test_foxglove_port_in_use_is_a_clear_error(tmp_path: Path) -> None:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        res = runner.invoke(
            app, ["teleop", "--input", "foxglove", "--port", str(port), "-o", str(tmp_path / "x.mcap")]
        )
    assert res.exit_code == 1 and "cannot start the Foxglove server" in res.output
    assert list(tmp_path.iterdir()) == []


# -- a taught three-goal task: scripted input → segment → estimate → execute ---------------------


@pytest.fixture(scope="module")
def taught(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A person's three-goal demonstration, scripted: the scripted teacher's commands replayed as
    Twists (as a client would send them), with pauses of a stop key now and then."""
    d = tmp_path_factory.mktemp("taught")
    teacher = d / "teacher.mcap"
    task = ROOT / "sample_logs" / "three-goals.task.yaml"
    res = runner.invoke(
        app,
        [
            "simulate",
            "--world",
            "building",
            "--teacher",
            str(task),
            "--duration",
            "400",
            "--seed",
            "1",
            "-o",
            str(teacher),
        ],
    )
    assert res.exit_code == 0, res.output
    entries = []
    shift = 0.0
    for i, (_, _, t, data) in enumerate(iter_messages(teacher, topics=["/cmd_vel"])):
        m = orjson.loads(data)
        if i in (150, 900):
            entries.append(key_entry(t / 1e9 + shift, "k"))
            shift += 2.0
        entries.append(twist_entry(t / 1e9 + shift, m["linear"]["x"], m["angular"]["z"]))
    entries.append(key_entry(entries[-1].t_ns / 1e9 + 0.5, "esc"))
    script = d / "drive.csv"
    script.write_text(write_csv(entries))
    demo = d / "demo.mcap"
    t0 = time.monotonic()
    res = runner.invoke(app, ["teleop", "--input", "script", "--script", str(script), "-o", str(demo)])
    assert res.exit_code == 0, res.output
    assert time.monotonic() - t0 < 30  # ~160 s of driving, faster than real time
    return demo


def test_a_taught_task_segments_by_its_goals(taught: Path) -> None:
    meta = file_info(taught).metadata["lfdfuse"]
    assert meta["teacher"] == "human" and meta["input"] == "script:drive.csv"
    assert [g.split("@")[0] for g in meta["goals"].split(",")] == ["red", "green", "blue"]
    report = json.loads(mcap_check(taught))
    assert report["ok"]
    res = runner.invoke(app, ["segment", str(taught)])
    assert res.exit_code == 0, res.output
    goals = re.findall(r"segment \d → (\S+):", res.output)
    assert goals[:3] == ["attract_red", "attract_green", "attract_blue"]
    assert "without heading information" in res.output  # the pauses


def test_the_learned_network_completes_the_taught_task(taught: Path, tmp_path: Path) -> None:
    seg = taught.with_name("demo.seg.mcap")
    if not seg.exists():
        assert runner.invoke(app, ["segment", str(taught)]).exit_code == 0
    table, run, report = tmp_path / "fusion.yaml", tmp_path / "run.mcap", tmp_path / "run.json"
    res = runner.invoke(app, ["estimate", str(seg), "-o", str(table)])
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        app,
        [
            "execute",
            str(table),
            "--start",
            "3.5,1.0,0.2",
            "--max-time",
            "300",
            "-o",
            str(run),
            "--report",
            str(report),
        ],
    )
    assert res.exit_code == 0, res.output
    assert json.loads(report.read_text())["completed"] is True
