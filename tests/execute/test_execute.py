"""The behaviour network runtime and `lfdfuse execute`: hierarchy, logs, reports, bad input."""

from __future__ import annotations

import json
import os
from dataclasses import replace
from pathlib import Path

import numpy as np
import orjson
import pytest
from typer.testing import CliRunner

from lfdfuse.behaviors.primitives import BehaviorOutputs
from lfdfuse.cli.main import app
from lfdfuse.errors import ConfigError
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.log.reader import iter_messages
from lfdfuse.network.runtime import NetworkRuntime
from lfdfuse.network.table import FusionRow, FusionTable, Network, Step, dump_table
from lfdfuse.world.model import load_world
from tests.conftest import mcap_check

runner = CliRunner()


def _outputs(k: int, bac: int) -> BehaviorOutputs:
    app_ = np.array([[bool(bac >> i & 1) for i in range(k)]])
    vec = np.zeros((1, k, 2))
    vec[0, :, 0] = app_[0] * 0.5
    return BehaviorOutputs(tuple(f"b{i}" for i in range(k)), vec, app_, np.zeros((1, k), dtype=bool))


def test_runtime_sequences_nested_goals_in_order() -> None:
    row = (FusionRow(bac=1, weights={"avoid": 1.0}),)
    leaf = lambda name, goal: Step(name, goal, row)  # noqa: E731
    inner = Network("inner", (leaf("a", "red"), leaf("b", "green")))
    middle = Network("middle", (Step("inner", None, (), inner), leaf("c", "blue")))
    table = FusionTable(
        ("avoid",), {"avoid": 1.0}, Network("top", (Step("middle", None, (), middle), leaf("d", "red")))
    )
    rt = NetworkRuntime(table)
    out = _outputs(1, 1)
    seen = []
    for reached in [set(), {"green"}, {"red"}, {"red"}, {"blue"}, {"green"}, {"red"}]:
        dec = rt.decide(out, reached)
        seen.append((dec.step.name if dec.step else None, dec.achieved_now))
    # green before red does not count (only the active step's goal is watched); red twice = two goals
    assert seen == [
        ("a", ()),
        ("a", ()),
        ("b", ("red",)),
        ("b", ()),
        ("b", ()),
        ("c", ("green",)),
        ("c", ()),
    ]
    assert rt.decide(out, {"blue"}).step.name == "d"  # type: ignore[union-attr]
    assert not rt.complete
    assert rt.decide(out, {"red"}).step is None and rt.complete


def test_unseen_bac_uses_default_weights() -> None:
    table = FusionTable(
        ("avoid", "wander"),
        {"wander": 1.0},
        Network("n", (Step("s", None, (FusionRow(1, {"avoid": 1.0}),)),)),
    )
    rt = NetworkRuntime(table)
    assert not rt.decide(_outputs(2, 1), set()).unseen
    dec = rt.decide(_outputs(2, 3), set())
    assert dec.unseen and dec.weights == {"wander": 1.0}


def test_a_network_nested_two_levels_drives_the_task(three_goal_table: FusionTable, tmp_path: Path) -> None:
    red, green, blue = three_goal_table.network.steps[:3]
    nested = Network(
        "task",
        (
            Step(
                "outer",
                None,
                (),
                Network("first-two", (Step("inner", None, (), Network("only-red", (red,))), green)),
            ),
            blue,
        ),
    )
    table = replace(three_goal_table, network=nested)
    res = run_table(
        ExecuteOptions(world=load_world("building"), table=table, max_time_s=300),
        out=tmp_path / "n.mcap",
        command="execute",
    )
    assert res.report["completed"]
    assert [g["target"] for g in res.report["goals"]] == ["red", "green", "blue"]
    steps = {json.loads(d)["step"] for t, _, _, d in iter_messages(tmp_path / "n.mcap", topics=["/lfd/step"])}
    assert "outer/inner/reach-red" in steps and "outer/reach-green" in steps and "reach-blue" in steps


def test_execute_cli_writes_log_report_and_overlay(three_goal_table: FusionTable, tmp_path: Path) -> None:
    (tmp_path / "t.yaml").write_text(dump_table(three_goal_table))
    res = runner.invoke(
        app,
        [
            "execute",
            str(tmp_path / "t.yaml"),
            "--max-time",
            "60",
            "-o",
            str(tmp_path / "r.mcap"),
            "--report",
            str(tmp_path / "r.json"),
        ],
    )
    assert res.exit_code == 0, res.output
    assert "goal reach-red (red): at" in res.output
    rep = json.loads((tmp_path / "r.json").read_text())
    for key in (
        "completed",
        "duration_s",
        "collisions",
        "path_length_m",
        "goals",
        "steps",
        "left_range_mean_m",
        "right_range_mean_m",
        "unseen_bac_fraction",
    ):
        assert key in rep
    assert rep["goals"][0]["reached"] and rep["goals"][0]["name"] == "reach-red"
    topics = {t for t, *_ in iter_messages(tmp_path / "r.mcap")}
    assert {
        "/scan",
        "/cmd_vel",
        "/lfd/behaviors",
        "/lfd/bac",
        "/lfd/step",
        "/lfd/fused",
        "/lfd/overlay",
    } <= topics
    overlay = [orjson.loads(d) for t, _, _, d in iter_messages(tmp_path / "r.mcap", topics=["/lfd/overlay"])]
    assert all(len(o["entities"][0]["arrows"]) >= 2 for o in overlay[:50])  # behaviours + fused
    assert json.loads(mcap_check(tmp_path / "r.mcap"))["ok"]


def test_execute_is_reproducible(three_goal_table: FusionTable, tmp_path: Path) -> None:
    for name in ("a", "b"):
        run_table(
            ExecuteOptions(
                world=load_world("building"),
                table=three_goal_table,
                max_time_s=20,
                seed=3,
                sensor_noise_m=0.01,
            ),
            out=tmp_path / f"{name}.mcap",
            command="execute",
        )
    assert (tmp_path / "a.mcap").read_bytes() == (tmp_path / "b.mcap").read_bytes()


def test_network_teacher_records_a_demonstration(three_goal_table: FusionTable, tmp_path: Path) -> None:
    (tmp_path / "t.yaml").write_text(dump_table(three_goal_table))
    res = runner.invoke(
        app,
        [
            "simulate",
            "--teacher",
            str(tmp_path / "t.yaml"),
            "--duration",
            "200",
            "-o",
            str(tmp_path / "d.mcap"),
        ],
    )
    assert res.exit_code == 0, res.output
    assert "network teacher" in res.output and "blue at" in res.output
    topics = {t for t, *_ in iter_messages(tmp_path / "d.mcap")}
    assert "/cmd_vel" in topics and not any(t.startswith("/lfd/") for t in topics)


def test_execute_bad_input(three_goal_table: FusionTable, tmp_path: Path) -> None:
    (tmp_path / "t.yaml").write_text(dump_table(three_goal_table))
    (tmp_path / "bad.yaml").write_text(
        "format: lfdfuse/fusion-table@1\nbehaviors: [avoid]\nnetwork: {steps: []}\n"
    )
    old = os.getcwd()
    os.chdir(tmp_path)
    try:
        for args, message in [
            (["execute", "bad.yaml"], "missing field 'default_weights'"),
            (
                ["execute", "t.yaml", "--world", "tee"],
                "needs targets red, green, blue that world 'tee' lacks",
            ),
            (["execute", "t.yaml", "--start", "0,0,0"], "start pose"),
            (["execute", "nothing.yaml"], "cannot read fusion table"),
        ]:
            before = sorted(os.listdir(tmp_path))
            res = runner.invoke(app, [*args, "-o", "r.mcap", "--report", "r.json"])
            assert res.exit_code == 1, res.output
            lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
            assert len(lines) == 1 and message in lines[0], res.stderr
            assert sorted(os.listdir(tmp_path)) == before
    finally:
        os.chdir(old)
    with pytest.raises(ConfigError, match="lacks"):
        run_table(
            ExecuteOptions(world=load_world("corridor"), table=three_goal_table),
            out=tmp_path / "x.mcap",
            command="execute",
        )


def test_corridor_style_ignores_openings() -> None:
    from lfdfuse.execute.report import corridor_style

    left = np.array([0.6, 0.6, 8.0, 8.0, 8.0, 0.7])  # doors on the left inflate a mean
    right = np.array([1.8, 1.8, 1.7, 1.8, 1.8, 1.7])
    assert corridor_style(left, right) == "left"
    assert corridor_style(right, left) == "right"
    assert corridor_style(np.full(4, 1.2), np.full(4, 1.25)) == "centre"
    assert corridor_style(np.full(3, 8.0), np.full(3, 1.0)) == "unknown"
