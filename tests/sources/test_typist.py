"""The keyboard person (``simulate --keys``): nearest key, held, logged as a teleop log."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import orjson
import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.control.command import DriveParams
from lfdfuse.log.reader import file_info, iter_messages
from lfdfuse.sources.teleop.keys import KeyState, press
from lfdfuse.sources.typist import key_headings, nearest_key
from tests.conftest import ROOT

runner = CliRunner()


@pytest.mark.parametrize("seed", range(5))
def test_the_nearest_key_points_nearest(seed: int) -> None:
    """Law: no other forward key's heading is nearer the wanted heading than the chosen one's."""
    rng = np.random.default_rng(seed)
    drive = DriveParams()
    table = key_headings(KeyState(), drive)
    for want in rng.uniform(-math.pi, math.pi, 200):
        key = nearest_key(float(want), drive)
        best = abs(math.remainder(want - table[key], math.tau))
        assert all(best <= abs(math.remainder(want - h, math.tau)) + 1e-12 for h in table.values())
    # a turn in place means "beyond the arcs": arcs at about 38°, turns in place at 90°
    assert table["u"] < table["j"] and table["o"] > table["l"]


def test_simulate_keys_is_a_teleop_log_of_held_keys(tmp_path: Path) -> None:
    outs = []
    for name in ("a", "b"):
        out = tmp_path / f"{name}.mcap"
        res = runner.invoke(
            app,
            [
                "simulate",
                "--world",
                "building",
                "--teacher",
                str(ROOT / "sample_logs" / "three-goals.task.yaml"),
            ]
            + ["--keys", "0.5", "--duration", "20", "--seed", "3", "-o", str(out)],
        )
        assert res.exit_code == 0, res.output
        outs.append(out)
    assert outs[0].read_bytes() == outs[1].read_bytes()  # same seed, same bytes
    info = file_info(outs[0])
    assert info.metadata["lfdfuse"]["teacher"] == "keyboard:three-goals.task.yaml"
    assert "/teleop/input" in info.channels
    keys = KeyState()
    allowed = {press(keys, k).state.command for k in ("i", "u", "o", "j", "l", "k")}
    cmds, presses = [], []
    for topic, _s, t, data in iter_messages(outs[0], topics=["/cmd_vel", "/teleop/input"]):
        m = orjson.loads(data)
        if topic == "/cmd_vel":
            cmds.append((t, (m["linear"]["x"], m["angular"]["z"])))
        else:
            presses.append(t)
    assert {c for _t, c in cmds} <= allowed
    gaps = np.diff(presses) / 1e9
    # jittered around the period (±40 %), on the 10 Hz clock
    assert 0.25 <= gaps.min() and gaps.max() <= 0.75 and abs(gaps.mean() - 0.5) < 0.1, gaps
    # held between presses: the command changes only at a press
    changes = [t for (t, c), (_t0, c0) in zip(cmds[1:], cmds[:-1], strict=True) if c != c0]
    assert set(changes) <= set(presses)


def test_keys_with_a_network_teacher_is_a_clean_error(tmp_path: Path) -> None:
    res = runner.invoke(
        app,
        [
            "simulate",
            "--teacher",
            str(ROOT / "lfdfuse" / "evaluate" / "truths" / "building-right.yaml"),
            "--keys",
            "0.5",
        ]
        + ["-o", str(tmp_path / "x.mcap")],
    )
    assert res.exit_code == 1
    assert res.output.strip().startswith("error:")
