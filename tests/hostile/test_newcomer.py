"""Defects a newcomer meets first, one test each, and the limits of the file readers (with hypothesis)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from lfdfuse import __version__
from lfdfuse.cli.main import app
from lfdfuse.cli.render import bac_names
from lfdfuse.errors import ConfigError, WorldError
from lfdfuse.files import MAX_YAML_DEPTH, parse_yaml
from lfdfuse.validate import validate
from lfdfuse.world.model import parse_world
from tests.hostile.base import TABLE_YAML
from tests.support.demo_check import problems

runner = CliRunner()


def test_version() -> None:
    res = runner.invoke(app, ["--version"])
    assert res.exit_code == 0 and res.stdout.strip() == f"lfdfuse {__version__}"


def test_a_goalless_run_is_not_reported_as_a_failed_task(tmp_path: Path) -> None:
    (tmp_path / "t.yaml").write_text(TABLE_YAML)
    old = os.getcwd()
    os.chdir(tmp_path)
    try:
        res = runner.invoke(
            app, ["execute", "t.yaml", "--world", "tee", "--start", "1,9,0", "--max-time", "2"]
        )
    finally:
        os.chdir(old)
    assert res.exit_code == 0, res.output
    assert "not completed" not in res.stdout and "without goals" in res.stdout
    assert "keeps the wall on its" in res.stdout or "keeps" in res.stdout


def test_an_unweighted_attract_needs_no_target_in_the_world(tmp_path: Path) -> None:
    table = (
        TABLE_YAML.replace("behaviors: [avoid,", "behaviors: [attract_red, attract_blue, avoid,")
        .replace("bac: 63", "bac: 252")
        .replace("bac: 31", "bac: 124")
    )
    (tmp_path / "t.yaml").write_text(table)
    res = runner.invoke(
        app,
        [
            "execute",
            str(tmp_path / "t.yaml"),
            "--world",
            "tee",
            "--max-time",
            "1",
            "-o",
            str(tmp_path / "r.mcap"),
        ],
    )
    assert res.exit_code == 0, res.output


def test_bac_in_words() -> None:
    assert (
        bac_names(
            37,
            (
                "avoid",
                "attract_red",
                "wander_left",
                "wander_right",
                "wall_attract_left",
                "wall_attract_right",
            ),
        )
        == "LA+WL+WFR"
    )
    assert bac_names(0, ("avoid",)) == "none"


def test_demo_check_says_when_learning_failed() -> None:
    good_left = {"left_range_mean_m": 0.7, "right_range_mean_m": 1.9, "collisions": 0}
    good_task = {"completed": True, "goals": [{"reached": True}]}
    assert problems(good_left, good_task) == []
    bad = problems(
        {**good_left, "left_range_mean_m": 2.5}, {"completed": False, "goals": [{"reached": False}]}
    )
    assert len(bad) == 2 and "keep left" in bad[0] and "0 of 1" in bad[1]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("walls: [[[0, 0], [10, 0], [10, 5], [0, 5], [0, 0]]]\nstart: [20, 20, 0]\n", "outside the map"),
        ("walls: [[[0, 0], [10, 0], [10, 5], [0, 5], [0, 0]]]\nstart: [0, 2, 0]\n", "wall"),
        (
            "walls: [[[0, 0], [1000000, 0], [1000000, 5], [0, 5], [0, 0]]]\nstart: [1, 2, 0]\n",
            "at most 500 m",
        ),
        ("walls: [[[0, 0], [10, 0]]]\nstart: [1, 2, 0]\nroof: tin\n", "unknown key 'roof'"),
        ("walls: [[[0, x], [10, 0]]]\nstart: [1, 2, 0]\n", "walls[0][0][1] must be a finite number"),
    ],
)
def test_world_errors_name_the_key_or_problem(text: str, message: str) -> None:
    with pytest.raises(WorldError, match=message.replace("[", r"\[").replace("]", r"\]")):
        parse_world(parse_yaml(text, origin="w.yaml"), origin="w.yaml")


def test_start_in_the_wrong_format_and_negative_noise_are_clear_errors(tmp_path: Path) -> None:
    """A pose in the wrong format, or a number out of the range ``--help`` shows, is a usage error
    naming the option (exit 2), before anything is written."""
    for args, message, code in (
        (["--start", "1 2 0"], "--start", 2),
        (["--sensor-noise", "-0.1"], "--sensor-noise", 2),
        (["--heading-noise", "inf"], "--heading-noise", 2),
        (["--duration", "1e12"], "--duration", 2),
        (["--seed", "-1"], "--seed", 2),
    ):
        res = runner.invoke(app, ["simulate", "--world", "tee", "-o", str(tmp_path / "x.mcap"), *args])
        where = res.stderr if code == 1 else res.output
        assert res.exit_code == code and message in where, (args, res.output)
        assert list(tmp_path.iterdir()) == []


def test_schema_errors_name_the_key() -> None:
    with pytest.raises(ConfigError, match=r"task\[1\]\.style: unknown value 'moonwalk'"):
        validate({"task": [{"style": "keep-left"}, {"style": "moonwalk"}]}, "task", origin="t.yaml")


_yaml_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=5),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=3), inner, max_size=3),
    max_leaves=20,
)


@settings(max_examples=60, deadline=None)
@given(depth=st.integers(0, 3 * MAX_YAML_DEPTH), flow=st.booleans())
def test_yaml_nesting_is_parsed_or_refused_never_a_crash(depth: int, flow: bool) -> None:
    text = "[" * depth + "]" * depth if flow else "".join(f"{'  ' * i}- \n" for i in range(depth)) or "x"
    try:
        parse_yaml(text, origin="f")
    except ConfigError as exc:
        assert "f:" in str(exc)


@settings(max_examples=60, deadline=None)
@given(value=_yaml_values)
def test_yaml_within_limits_round_trips(value: object) -> None:
    import yaml

    assert parse_yaml(yaml.safe_dump(value), origin="f") == value


@settings(max_examples=30, deadline=None)
@given(fan=st.integers(2, 12), levels=st.integers(1, 9))
def test_anchor_expansion_is_bounded(fan: int, levels: int) -> None:
    lines = ["a0: &a0 [x]"] + [
        f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * fan)}]" for i in range(1, levels + 1)
    ]
    text = "\n".join(lines) + "\n"
    try:
        parse_yaml(text, origin="f")
    except ConfigError as exc:
        assert "anchor bomb" in str(exc)
        assert fan**levels > 100_000
