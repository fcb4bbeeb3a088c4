"""``teleop --table``: the network drives, a person corrects; who drove, what the network proposed,
and where it asked for help are in the log (DESIGN §5, §8, §10)."""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import orjson
import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.execute.correct import CorrectionResult, correct, correction_driver
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.log import lfd
from lfdfuse.log.reader import file_info, iter_messages
from lfdfuse.network.table import FusionTable, dump_table, load_table
from lfdfuse.robot.pose import Pose
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sources.teleop.clock import SimClock
from lfdfuse.sources.teleop.inputs import Input, decode_teleop_input
from lfdfuse.sources.teleop.script import ScriptInput, parse_yaml
from lfdfuse.sources.teleop.session import TeleopOptions, make_session
from tests.conftest import ROOT, mcap_check
from tests.sources.teleop.correction import CORRIDOR_TABLE, Fed

runner = CliRunner()
DT_NS = 100_000_000


def _table() -> FusionTable:
    return load_table(CORRIDOR_TABLE)


def _correct(
    tmp: Path,
    inputs: dict[float, list[Input]],
    *,
    table: FusionTable | None = None,
    seed: int = 0,
    noise_m: float = 0.0,
    start: Pose | None = None,
    duration_s: float = 10.0,
    handback_s: float | None = None,
    name: str = "c.mcap",
) -> tuple[CorrectionResult, Path]:
    sensors = SensorParams().with_noise(noise_m) if noise_m > 0 else SensorParams()
    opts = TeleopOptions(
        world=_world(),
        input_name="test",
        seed=seed,
        start=start,
        duration_s=duration_s,
        sensors=sensors,
        handback_s=handback_s,
    )
    driver = correction_driver(opts, table or _table())
    session = make_session(opts, inputs=[Fed(inputs)], clock=SimClock(), network=driver)
    out = tmp / name
    return correct(opts, session=session, driver=driver, table_name="corridor.yaml", out=out), out


def _world() -> Any:
    from lfdfuse.world.model import load_world

    return load_world("corridor")


def _by_tick(path: Path, topic: str) -> dict[int, bytes]:
    return {t: d for _, _, t, d in iter_messages(path, topics=[topic])}


def key(k: str) -> list[Input]:
    return [Input("key", k, "keyboard")]


def twist(v: float, w: float) -> list[Input]:
    payload = json.dumps({"linear": {"x": v}, "angular": {"z": w}})
    return [Input("message", payload, "client", "geometry_msgs/Twist")]


# -- until the first input, it is the execute run ----------------------------------------------


@pytest.mark.parametrize(
    ("seed", "noise_m", "start"),
    [(0, 0.0, None), (3, 0.02, Pose(3.0, 1.0, 0.3)), (11, 0.05, Pose(2.0, 1.4, -0.2))],
)
def test_until_the_first_input_the_run_is_the_execute_run(
    tmp_path: Path, seed: int, noise_m: float, start: Pose | None
) -> None:
    first_s = 5.0
    _, corr = _correct(
        tmp_path, {first_s: key("j"), 7.0: key("h")}, seed=seed, noise_m=noise_m, start=start, duration_s=10.0
    )
    ex = tmp_path / "x.mcap"
    run_table(
        ExecuteOptions(
            world=_world(), table=_table(), start=start, max_time_s=10.0, seed=seed, sensor_noise_m=noise_m
        ),
        out=ex,
        command="execute",
    )
    cut = round(first_s * 1e9)
    for topic in ("/lfd/fused", "/pose", "/lfd/step", "/scan", "/cmd_vel"):
        a, b = _by_tick(ex, topic), _by_tick(corr, topic)
        before = sorted(t for t in a if t < cut)
        assert len(before) == first_s * 10 and before == sorted(t for t in b if t < cut), topic
        assert all(a[t] == b[t] for t in before), topic
    # and at the input the person's command differs: the comparison can fail
    assert _by_tick(ex, "/cmd_vel")[cut] != _by_tick(corr, "/cmd_vel")[cut]


def test_without_input_the_whole_run_is_the_execute_run(tmp_path: Path) -> None:
    _, corr = _correct(tmp_path, {}, seed=5, noise_m=0.03, duration_s=6.0)
    ex = tmp_path / "x.mcap"
    run_table(
        ExecuteOptions(world=_world(), table=_table(), max_time_s=6.0, seed=5, sensor_noise_m=0.03),
        out=ex,
        command="execute",
    )
    for topic in ("/lfd/fused", "/pose", "/lfd/step", "/lfd/behaviors"):
        assert _by_tick(ex, topic) == _by_tick(corr, topic), topic
    auth = [lfd.decode_authority(d) for d in _by_tick(corr, "/lfd/authority").values()]
    assert len(auth) == 61 and not any(a.person for a in auth)


def test_segment_keeps_a_corrections_network_step_and_who_drove(tmp_path: Path) -> None:
    """Segmented, a correction keeps ``/lfd/step`` and ``/lfd/authority`` message for message (the
    network's sub-step at each tick is what estimate learns a correction in), read back per tick
    by :func:`network_steps`, and the file still passes the independent MCAP check."""
    from lfdfuse.segment.pipeline import segment_file
    from lfdfuse.segment.read import network_steps, read_segmented

    _, corr = _correct(
        tmp_path, {1.0: key("i"), 2.0: [Input("handback", "", "script")]}, seed=5, duration_s=4.0
    )
    seg = tmp_path / "c.seg.mcap"
    segment_file(corr, out=seg, behaviors=",".join(_table().behaviors), measure_lag=False)
    for topic in ("/lfd/step", "/lfd/authority"):
        assert _by_tick(seg, topic) == _by_tick(corr, topic), topic
    run = read_segmented(seg)
    steps = network_steps(seg, run.t_ns)
    want = [lfd.NetworkStep.decode(d).step for _, d in sorted(_by_tick(corr, "/lfd/step").items())]
    assert steps is not None and list(steps) == want and len(want) == len(run.t_ns)
    assert network_steps(tmp_path / "c.seg.mcap", run.t_ns[:3]) == tuple(want[:3])
    mcap_check(seg)


# -- who drives --------------------------------------------------------------------------------


def test_a_key_takes_over_at_once_and_h_gives_control_back(tmp_path: Path) -> None:
    result, out = _correct(tmp_path, {3.0: key("i"), 5.0: key("h")}, duration_s=8.0)
    auth = _by_tick(out, "/lfd/authority")
    fused = _by_tick(out, "/lfd/fused")
    cmds = {t: orjson.loads(d) for t, d in _by_tick(out, "/cmd_vel").items()}
    assert sorted(auth) == sorted(fused) == sorted(cmds)  # every tick: who drove, what the network proposed
    person = sorted(t for t, d in auth.items() if lfd.decode_authority(d).person)
    assert person == [k * DT_NS for k in range(30, 50)]
    assert {lfd.decode_authority(auth[t]).source for t in person} == {"keyboard"}
    assert all((cmds[t]["linear"]["x"], cmds[t]["angular"]["z"]) == (0.4, 0.0) for t in person)
    effects = [decode_teleop_input(orjson.loads(d)).effect for d in _by_tick(out, "/teleop/input").values()]
    assert effects[:2] == ["move", "handback"]
    assert result.report["correction"] == {
        "person_ticks": 20,
        "network_ticks": 61,
        "takeovers": 1,
        "person_collisions": 0,
    }


def test_a_client_twist_takes_over_and_handback_seconds_without_input_return_it(tmp_path: Path) -> None:
    inputs = {
        1.0: [Input("message", "nonsense", "client", "geometry_msgs/Twist")],  # invalid: no takeover
        2.0: twist(0.2, 0.5),
        2.5: twist(0.2, 0.5),
    }
    result, out = _correct(tmp_path, inputs, duration_s=6.0, handback_s=1.5)
    auth = {t: lfd.decode_authority(d) for t, d in _by_tick(out, "/lfd/authority").items()}
    person = sorted(t for t, a in auth.items() if a.person)
    assert person == [k * DT_NS for k in range(20, 40)]  # 1.5 s after the last input, at 4.0 s
    assert {auth[t].source for t in person} == {"client"}
    recs = [decode_teleop_input(orjson.loads(d)) for d in _by_tick(out, "/teleop/input").values()]
    assert [(r.effect, r.input) for r in recs if r.effect == "handback"] == [
        ("handback", "no input for 1.5 s")
    ]
    assert result.report["correction"]["takeovers"] == 1


def test_the_run_ends_when_the_network_completes_its_task(tmp_path: Path) -> None:
    from lfdfuse.network.table import Network, Step
    from lfdfuse.sources.teleop.session import teleop  # noqa: F401 (the session runs inside correct)
    from lfdfuse.world.model import load_world

    world = load_world("building")
    red = world.target("red")
    table = FusionTable(
        ("avoid", "attract_red"), {"attract_red": 1.0}, Network("go", (Step("reach-red", "red"),))
    )
    opts = TeleopOptions(
        world=world, input_name="test", start=Pose(red.x, red.y - 2.0, 1.5708), duration_s=30.0
    )
    driver = correction_driver(opts, table)
    session = make_session(opts, inputs=[Fed({})], clock=SimClock(), network=driver)
    result = correct(opts, session=session, driver=driver, table_name="r.yaml", out=tmp_path / "r.mcap")
    assert result.teleop.ended == "task complete" and result.report["completed"] is True
    assert result.teleop.run.steps < 100  # well before the duration
    assert {h["why"] for h in result.report["help"]} == {"unseen BAC"}  # a table without rows


def test_a_script_can_hand_back_and_the_network_drives_on_after_it() -> None:
    entries = parse_yaml([{"t": 1.0, "key": "i"}, {"t": 2.0, "handback": True}])
    assert [e.input.kind for e in entries] == ["key", "handback"]
    assert ScriptInput(entries).entries[-1].input.kind == "end"  # plain teleop ends with the script
    assert [e.input.kind for e in ScriptInput(entries, end_with_last=False).entries] == ["key", "handback"]
    with pytest.raises(Exception, match="handback must be true"):
        parse_yaml([{"t": 1.0, "handback": "yes"}])


def test_without_a_network_a_handback_changes_nothing(tmp_path: Path) -> None:
    from lfdfuse.sources.teleop.session import teleop

    opts = TeleopOptions(world=_world(), input_name="test", duration_s=2.0)
    session = make_session(
        opts, inputs=[Fed({0.0: key("i"), 1.0: [Input("handback", "", "script")]})], clock=SimClock()
    )
    teleop(opts, session=session, out=tmp_path / "p.mcap")
    assert session.authority == "person" and "/lfd/authority" not in _topics(tmp_path / "p.mcap")
    cmds = [orjson.loads(d)["linear"]["x"] for d in _by_tick(tmp_path / "p.mcap", "/cmd_vel").values()]
    assert cmds[15] == 0.4  # still driving forward


def _topics(path: Path) -> set[str]:
    return set(file_info(path).channels)


# -- asking for help ---------------------------------------------------------------------------


def _unsure(table: FusionTable) -> FusionTable:
    """The corridor table with its BAC-31 row marked not identifiable."""
    step = table.network.steps[0]
    rows = tuple(replace(r, identifiable=False) if r.bac == 31 else r for r in step.fusion)
    return replace(table, network=replace(table.network, steps=(replace(step, fusion=rows),)))


def _without_31(table: FusionTable) -> FusionTable:
    """The corridor table without its BAC-31 row (the corridor's usual BAC: default weights drive)."""
    step = table.network.steps[0]
    rows = tuple(r for r in step.fusion if r.bac != 31)
    return replace(table, network=replace(table.network, steps=(replace(step, fusion=rows),)))


@pytest.mark.parametrize(
    ("variant", "why"), [(_unsure, "not identifiable"), (_without_31, "unseen BAC")], ids=["unsure", "unseen"]
)
def test_help_is_asked_when_a_condition_begins_and_reported(tmp_path: Path, variant: Any, why: str) -> None:
    table = variant(_table())
    result, out = _correct(tmp_path, {}, table=table, seed=2, noise_m=0.05, duration_s=6.0)
    rows = {r.bac: r for r in table.network.steps[0].fusion}
    steps = [lfd.NetworkStep.decode(d) for _, d in sorted(_by_tick(out, "/lfd/step").items())]
    want, prev = [], None
    for s in steps:
        need = (
            "unseen BAC"
            if s.default_weights
            else ("not identifiable" if rows[s.bac].identifiable is False else None)
        )
        cond = None if need is None else (s.step, s.bac, need)
        if cond is not None and cond != prev:
            want.append((s.t_ns, *cond))
        prev = cond
    got = [
        (e.t_ns, e.step, e.bac, e.why)
        for e in map(lfd.decode_network_event, _by_tick(out, "/lfd/network").values())
    ]
    assert got == want and why in {w for *_, w in got}
    assert len(got) < len(steps) / 4  # once when a condition begins, not on every tick it lasts
    assert result.report["help"] == [
        {"t_s": round(t / 1e9, 2), "step": s, "bac": b, "why": w} for t, s, b, w in got
    ]


def test_execute_reports_help_too_and_a_sure_table_asks_for_none(tmp_path: Path) -> None:
    sure = _table()
    step = sure.network.steps[0]
    everything = replace(
        sure,
        network=replace(
            sure.network,
            steps=(replace(step, fusion=tuple(replace(step.fusion[0], bac=b) for b in range(64))),),
        ),
    )
    rep = run_table(
        ExecuteOptions(world=_world(), table=everything, max_time_s=5.0), out=tmp_path / "a.mcap", command="t"
    ).report
    assert rep["help"] == [] and _by_tick(tmp_path / "a.mcap", "/lfd/network") == {}
    rep = run_table(
        ExecuteOptions(world=_world(), table=_unsure(sure), max_time_s=5.0),
        out=tmp_path / "b.mcap",
        command="t",
    ).report
    assert rep["help"] and rep["help"][0]["why"] in ("unseen BAC", "not identifiable")


# -- the command -------------------------------------------------------------------------------


def test_teleop_table_from_the_command_line(tmp_path: Path) -> None:
    table = tmp_path / "t.yaml"
    table.write_text(dump_table(_unsure(_table())))
    script = tmp_path / "fix.yaml"
    script.write_text("- {t: 2.0, key: u}\n- {t: 3.0, handback: true}\n")
    out, report = tmp_path / "fix.mcap", tmp_path / "fix.json"
    args = ["teleop", "--table", str(table), "--world", "corridor", "--input", "script"]
    res = runner.invoke(
        app, [*args, "--script", str(script), "--duration", "6", "-o", str(out), "--report", str(report)]
    )
    assert res.exit_code == 0, res.output
    assert "asked for help" in res.output and "the person drove 10 ticks" in res.output
    rep = json.loads(report.read_text())
    assert rep["correction"]["person_ticks"] == 10 and rep["help"]
    meta = file_info(out).metadata["lfdfuse"]
    assert meta["teacher"] == "human" and meta["table"] == "t.yaml" and meta["corrects"] == "network"
    assert len(_by_tick(out, "/lfd/authority")) == 61  # the run went on after the script's last entry
    mcap_check(out)


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--handback", "2"], "--handback, --report and --demo go with --table"),
        (["--table", str(CORRIDOR_TABLE), "--estimate-to", "x.yaml"], "--estimate-to needs the demos"),
        (["--table", "missing.yaml"], "missing.yaml"),
    ],
)
def test_bad_table_options_are_one_line_errors(tmp_path: Path, extra: list[str], needle: str) -> None:
    script = tmp_path / "s.yaml"
    script.write_text("- {t: 0.5, key: i}\n")
    res = runner.invoke(
        app, ["teleop", "--input", "script", "--script", str(script), "-o", str(tmp_path / "o.mcap"), *extra]
    )
    assert res.exit_code == 1 and needle in res.output and "Traceback" not in res.output
    assert not (tmp_path / "o.mcap").exists()


def test_the_sample_correction_log_marks_the_persons_ticks(tmp_path: Path) -> None:
    from tests.sources.teleop.correction import correction_log

    path, person = correction_log(tmp_path)
    auth = {t: lfd.decode_authority(d).person for t, d in _by_tick(path, "/lfd/authority").items()}
    assert sorted(t for t, p in auth.items() if p) == person and 0 < len(person) < len(auth)
    assert (ROOT / "schemas" / "lfdfuse.Authority.json").exists()


def test_keyboard_correction_in_a_terminal_shows_who_drives(tmp_path: Path) -> None:
    from tests.sources.test_teleop import Pty

    out = tmp_path / "k.mcap"
    term = Pty(["teleop", "--table", str(CORRIDOR_TABLE), "--world", "corridor", "-o", str(out)])
    term.wait_for(b"driving: NETWORK")
    term.send(b"j", 0.0)
    term.wait_for(b"driving: PERSON")
    n = len(term.out)
    term.send(b"h", 0.0)
    end = time.monotonic() + 10
    while b"driving: NETWORK" not in term.out[n:] and time.monotonic() < end:
        term.pump(0.1)
    assert b"driving: NETWORK" in term.out[n:]
    assert b"hand control back" in term.out  # the key help names h
    term.send(b"\x03", 0.0)
    assert term.finish() == 0, term.text()[-3000:]
    who = [lfd.decode_authority(d).authority for _, d in sorted(_by_tick(out, "/lfd/authority").items())]
    first = who.index("person")
    assert who[0] == "network" and "network" in who[first:]  # taken over, then handed back


def test_a_collision_while_the_person_drives_is_the_persons_not_the_networks(tmp_path: Path) -> None:
    """The person turns to the wall and drives into it: the correction entry counts the collision
    as the person's, and the network's report (its verdict) does not."""
    inputs: dict[float, list[Input]] = {1.0 + 0.25 * k: twist(0.0, 1.0) for k in range(7)}
    inputs |= {2.75 + 0.25 * k: twist(0.4, 0.0) for k in range(16)}
    result, _out = _correct(tmp_path, inputs, duration_s=9.0, handback_s=1.0)
    c = result.report["correction"]
    assert c["takeovers"] == 1 and c["person_collisions"] >= 1, c
    assert result.report["collisions"] + c["person_collisions"] == result.teleop.run.collisions
    assert result.report["collisions"] == result.teleop.run.collisions - c["person_collisions"]


def test_teleop_table_with_its_demo_says_what_the_correction_changes(tmp_path: Path) -> None:
    """After the session, the estimate with the demo and the correction: one line per step it
    re-weights, and (--estimate-to) the table itself, the same as `estimate demo fix` gives."""
    from lfdfuse.learn import demonstrate, learn
    from lfdfuse.segment.pipeline import segment_file
    from lfdfuse.world.model import load_world
    from tests.sources.teleop.correction import CORRECTION_SCRIPT

    truth = load_table(CORRIDOR_TABLE)
    demo = demonstrate(
        truth, world=load_world("corridor"), folder=tmp_path, name="d", duration_s=14.0, seed=1
    )
    script = tmp_path / "fix.yaml"
    script.write_text("".join(f"- {json.dumps(e)}\n" for e in CORRECTION_SCRIPT))
    out, fixed = tmp_path / "fix.mcap", tmp_path / "fixed.yaml"
    args = ["teleop", "--table", str(CORRIDOR_TABLE), "--world", "corridor", "--input", "script"]
    res = runner.invoke(
        app,
        [*args, "--script", str(script), "--duration", "14", "-o", str(out), "--demo", str(demo.segmented)]
        + ["--estimate-to", str(fixed)],
    )
    assert res.exit_code == 0, res.output
    assert f"estimated with 1 demo and this correction (written to {fixed})" in res.output
    step = truth.network.steps[0].name
    line = next(ln.strip() for ln in res.output.splitlines() if ln.strip().startswith(f"{step}: re-weights"))
    assert int(line.split()[2]) >= 1, line  # the rows the person drove in
    seg = tmp_path / "fix.seg.mcap"
    segment_file(out, out=seg, behaviors=",".join(truth.behaviors))
    assert fixed.read_text() == dump_table(learn([demo.segmented, seg]).table)
