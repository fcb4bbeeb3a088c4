"""``teacher_from``: a ``--teacher`` spec into a typed teacher, every error before a run."""

from __future__ import annotations

from pathlib import Path

import pytest

from lfdfuse.errors import ConfigError, LfdError, WorldError
from lfdfuse.files import read_yaml
from lfdfuse.network.table import parse_table, write_table
from lfdfuse.sources.tasks import STYLES, load_task
from lfdfuse.sources.teachers import NetworkTeacher, ScriptedTeacher, teacher_from
from lfdfuse.world.model import load_world

SAMPLES = Path(__file__).resolve().parents[2] / "sample_logs"
BUILDING = load_world("building")


@pytest.mark.parametrize("style", STYLES)
def test_a_style_tours_in_that_style(style: str) -> None:
    spec = teacher_from(style, BUILDING)
    assert isinstance(spec, ScriptedTeacher)
    assert spec.name == style and [(leg.target, leg.style) for leg in spec.legs] == [(None, style)]


def test_a_task_file_gives_its_legs() -> None:
    path = SAMPLES / "three-goals.task.yaml"
    spec = teacher_from(str(path), BUILDING)
    assert isinstance(spec, ScriptedTeacher)
    assert list(spec.legs) == load_task(str(path)) and spec.name == path.name


def test_a_table_is_a_network_teacher_whose_table_round_trips(tmp_path: Path) -> None:
    t = tmp_path / "t.yaml"
    (tmp_path / "src.yaml").write_text(
        "format: lfdfuse/fusion-table@1\nbehaviors: [avoid, wander_left]\n"
        "default_weights: {avoid: 0.5, wander_left: 0.5}\n"
        "network: {name: n, steps: [{name: free, goal: null, fusion: [{bac: 3, weights: {avoid: 1.0}}]}]}\n"
    )
    table = parse_table(read_yaml(tmp_path / "src.yaml", what="table"))
    write_table(table, t)
    spec = teacher_from(str(t), BUILDING)
    assert isinstance(spec, NetworkTeacher) and spec.name == "t.yaml" and spec.path == t
    assert parse_table(spec.data) == table


@pytest.mark.parametrize(
    ("content", "error", "needle"),
    [
        ("task:\n  - {target: purple, style: keep-left}\n", WorldError, "no target 'purple'"),
        ("task:\n  - {target: red, style: moonwalk}\n", ConfigError, "unknown teacher style"),
        ("walls: [[[0, 0], [1, 0]]]\nstart: [0.5, 0.5, 0]\n", ConfigError, "a task file"),
        ("- 1\n- 2\n", ConfigError, "a task file"),
        ("task: [\n", ConfigError, "malformed YAML"),
    ],
)
def test_a_bad_file_is_one_error(tmp_path: Path, content: str, error: type[LfdError], needle: str) -> None:
    p = tmp_path / "x.yaml"
    p.write_text(content)
    with pytest.raises(error, match=needle):
        teacher_from(str(p), BUILDING)


@pytest.mark.parametrize("spec", ["zigzag", "", "x" * 5000, "missing.yaml"])
def test_neither_a_style_nor_a_file_is_one_error(spec: str) -> None:
    with pytest.raises(ConfigError):
        teacher_from(spec, BUILDING)
