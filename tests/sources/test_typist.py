"""The keyboard person (``simulate --keys``): nearest key, held, logged as a teleop log."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import orjson
import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.control.command import DriveParams, heading_to_command
from lfdfuse.log.reader import file_info, iter_messages
from lfdfuse.sources.teleop.keys import KeyState, press
from lfdfuse.sources.typist import (
    CHOICES,
    PERSONS,
    KeyboardParams,
    KeyboardPerson,
    key_headings,
    nearest_key,
    threshold_key,
)
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


class _Wants:
    """A teacher wanting ``heading(k)`` (robot frame, rad) at tick k; never done."""

    def __init__(self, heading: Callable[[int], float], drive: DriveParams) -> None:
        self.heading, self.drive = heading, drive
        self.done = False
        self.reached: list[tuple[str, int]] = []

    def command(self, obs: Any) -> tuple[float, float]:
        v, w = heading_to_command(np.array(self.heading(obs.k)), self.drive)
        return float(v), float(w)


#: the laser of :func:`_drive`'s scenes: a beam every degree all around
BEAMS = np.radians(np.arange(-180.0, 180.0, 1.0))
OPEN = np.full(len(BEAMS), 10.0)


def _drive(
    person: KeyboardPerson,
    ticks: int,
    *,
    theta: Callable[[int], float] = lambda k: 0.0,
    ranges: Callable[[int], np.ndarray] = lambda k: OPEN,
) -> list[tuple[int, str]]:
    """Every press ``(tick, key)`` of ``ticks`` control periods, the robot heading ``theta(k)``
    and its laser reading ``ranges(k)`` at tick k (open all around by default)."""
    out = []
    for k in range(ticks):
        obs = SimpleNamespace(
            k=k, pose=SimpleNamespace(theta=theta(k)), reading=SimpleNamespace(ranges_m=ranges(k))
        )
        person.command(obs)  # type: ignore[arg-type]
        out += [(t, inp.text) for t, inp, _cmd in person.presses]
        person.presses.clear()
    return out


def _person(heading: Callable[[int], float], params: KeyboardParams, seed: int = 0) -> KeyboardPerson:
    drive = DriveParams()
    return KeyboardPerson(
        _Wants(heading, drive),
        drive=drive,
        dt_s=0.1,
        rng=np.random.default_rng(seed),
        params=params,
        beam_angles_rad=BEAMS,
    )


def test_the_zoo_spans_the_documented_ranges() -> None:
    """Every named person is a valid model; together they span reaction 0–0.6 s, periods 0.3–1.5 s,
    both ways of choosing a key, slips, stop-and-go and cut corners."""
    assert len(PERSONS) >= 7 and PERSONS["steady"] == KeyboardParams()
    for p in PERSONS.values():
        p.check()
        assert 0.0 <= p.reaction_s <= 0.6 and 0.3 <= p.period_s <= 1.5
    ps = list(PERSONS.values())
    assert min(p.reaction_s for p in ps) == 0.0 and max(p.reaction_s for p in ps) == 0.6
    assert {p.choice for p in ps} == set(CHOICES)
    assert any(p.lapse > 0 for p in ps) and any(p.stop_go > 0 for p in ps) and any(p.corner_m > 0 for p in ps)
    # every person but steady sees the robot's own turn and does not hold a key into a wall
    assert all(p.sees_turn and p.reflex_m > 0 for name, p in PERSONS.items() if name != "steady")


@pytest.mark.parametrize("name", ["prompt", "steady", "late"])
def test_a_press_answers_what_was_wanted_reaction_ago(name: str) -> None:
    """The wanted turn flips from hard left to hard right at tick 50: the first right key comes
    ``reaction_s`` after the flip (at the first press after it), never earlier."""
    params = replace(PERSONS[name], jitter=0.0, period_s=0.1)  # a look every tick
    presses = _drive(_person(lambda k: 1.5 if k < 50 else -1.5, params), 80)
    first_right = min(t for t, key in presses if key == "l")
    assert first_right == 50 + round(params.reaction_s / 0.1), presses


def test_thresholds_choose_by_the_size_of_the_turn() -> None:
    for deg, key in [
        (0, "i"),
        (10, "i"),
        (-29, "i"),
        (31, "u"),
        (-31, "o"),
        (79, "u"),
        (81, "j"),
        (-170, "l"),
    ]:
        assert threshold_key(math.radians(deg), 30.0, 80.0) == key, deg
    # a coarse person keeps straight where the nearest-heading person already arcs
    assert nearest_key(math.radians(25), DriveParams()) == "u"
    assert threshold_key(math.radians(25), 30.0, 80.0) == "i"


def test_slips_press_wrong_keys_and_miss_presses() -> None:
    """Wanting straight ahead: a careful person presses only ``i``; one slipping a third of the
    time presses neighbours (``u``/``o``) and misses presses (fewer than one per look)."""
    careful = _drive(_person(lambda k: 0.0, replace(KeyboardParams(), jitter=0.0)), 600)
    sloppy = _drive(_person(lambda k: 0.0, replace(KeyboardParams(), jitter=0.0, lapse=0.33)), 600)
    assert {key for _t, key in careful} == {"i"} and len(careful) == 120
    wrong = sum(key in ("u", "o") for _t, key in sloppy)
    assert {key for _t, key in sloppy} <= {"i", "u", "o"}
    assert 8 <= wrong <= 40 and 85 <= len(sloppy) <= 112, (wrong, len(sloppy))


def test_stop_and_go_stops_while_the_teacher_drives() -> None:
    params = replace(KeyboardParams(), stop_go=0.2, pause_s=1.0)
    presses = _drive(_person(lambda k: 0.3, params), 600)
    stops = [t for t, key in presses if key == "k"]
    assert 5 <= len(stops) <= 40, stops
    # each stop is held for the pause (and the next look): no key within 1 s after a stop
    nxt = {t: min((u for u, _k in presses if u > t), default=10**9) for t in stops}
    assert all(nxt[t] - t >= 10 + round(0.5 * 0.6 * 10) for t in stops), nxt


def test_simulate_person_is_recorded_and_steady_keys_are_not(tmp_path: Path) -> None:
    task = str(ROOT / "sample_logs" / "three-goals.task.yaml")
    base = ["simulate", "--world", "building", "--teacher", task, "--duration", "15", "--seed", "4"]
    outs = {}
    for name, extra in [
        ("keys", ["--keys", "0.5"]),
        ("sloppy", ["--person", "sloppy"]),
        ("sloppy2", ["--person", "sloppy"]),
        (
            "custom",
            ["--keys", "0.9", "--reaction", "0.4", "--thresholds", "25,70", "--reflex", "0.3", "--sees-turn"],
        ),
    ]:
        out = tmp_path / f"{name}.mcap"
        res = runner.invoke(app, base + extra + ["-o", str(out)])
        assert res.exit_code == 0, res.output
        outs[name] = file_info(out).metadata["lfdfuse"]
    assert "person" not in outs["keys"] and outs["keys"]["input"] == "keys:0.5"
    assert outs["sloppy"]["person"] == "sloppy" and outs["sloppy"]["input"] == "keys:0.6"
    assert "lapse=0.16" in outs["sloppy"]["person_model"]
    assert (tmp_path / "sloppy.mcap").read_bytes() == (tmp_path / "sloppy2.mcap").read_bytes()
    assert outs["custom"]["person"] == "custom" and outs["custom"]["input"] == "keys:0.9"
    model = outs["custom"]["person_model"]
    assert "choice='thresholds'" in model and "arc_deg=25.0" in model and "reaction_s=0.4" in model
    assert "reflex_m=0.3" in model and "sees_turn=True" in model


@pytest.mark.parametrize(
    "extra",
    [["--person", "nobody"], ["--thresholds", "70,20"], ["--thresholds", "x"], ["--choose", "best"]],
)
def test_a_bad_person_is_a_clean_error(tmp_path: Path, extra: list[str]) -> None:
    res = runner.invoke(app, ["simulate", "--duration", "5", *extra, "-o", str(tmp_path / "x.mcap")])
    assert res.exit_code == 1, res.output
    assert res.output.strip().startswith("error:"), res.output
    assert not (tmp_path / "x.mcap").exists()


def test_a_person_who_sees_the_turn_does_not_overshoot_it() -> None:
    """The robot turns from 0 to 1 rad over the first 10 ticks toward a direction 1 rad to the
    left, then holds it: the teacher wants ``1 − θ``. A person reacting 0.6 s late sees at tick 12
    the want of tick 6 (0.4 rad: an arc); one who sees the robot's turn since allows for the
    0.4 rad turned and drives straight, as the teacher now wants."""
    theta = lambda k: min(0.1 * k, 1.0)  # noqa: E731
    want = lambda k: 1.0 - theta(k)  # noqa: E731
    late = replace(KeyboardParams(), jitter=0.0, period_s=0.1, reaction_s=0.6)
    blind = dict(_drive(_person(want, late), 20, theta=theta))
    seeing = dict(_drive(_person(want, replace(late, sees_turn=True)), 20, theta=theta))
    assert [blind[k] for k in (11, 12)] == ["u"] * 2, blind
    assert all(seeing[k] == "i" for k in range(11, 20) if k in seeing), seeing


def test_a_person_with_a_reflex_never_holds_a_key_into_a_wall() -> None:
    """Wanting straight ahead, a wall appears 0.4 m ahead at tick 20: a person with a 0.5 m
    reflex who looks only every 1.5 s takes the hand off ``i`` at once (a turn in place, the
    only keys that do not drive into it) and never presses ``i`` while the wall is there;
    without the reflex ``i`` is held into the wall until the next look."""
    wall = np.where(np.abs(BEAMS) < math.radians(80), 0.4 / np.cos(np.clip(BEAMS, -1.39, 1.39)), 10.0)
    ranges = lambda k: OPEN if k < 20 else wall  # noqa: E731
    base = replace(KeyboardParams(), jitter=0.0, period_s=1.5, reaction_s=0.0)
    careful = _drive(_person(lambda k: 0.0, replace(base, reflex_m=0.5)), 60, ranges=ranges)
    careless = _drive(_person(lambda k: 0.0, base), 60, ranges=ranges)
    assert careful[:2] == [(0, "i"), (15, "i")] and careful[2] == (20, "j"), careful
    assert all(key in ("j", "l") for t, key in careful if t >= 20), careful
    assert (30, "i") in careless and all(t % 15 == 0 for t, _key in careless), careless
