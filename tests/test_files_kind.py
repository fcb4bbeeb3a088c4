"""``files.kind_of``: which of our YAML files a document is, by its top level."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import yaml
from hypothesis import given
from hypothesis import strategies as st

from lfdfuse.files import YamlKind, kind_of, read_yaml
from lfdfuse.network.table import default_weights_for, parse_table
from lfdfuse.world.model import builtin_names

SAMPLES = Path(__file__).resolve().parents[1] / "sample_logs"

keys = st.text(min_size=1, max_size=8)
values = st.none() | st.integers() | st.text(max_size=5)


def test_every_shipped_file_is_told_for_what_it_is() -> None:
    for name in builtin_names():
        text = (resources.files("lfdfuse") / "world" / "builtin" / f"{name}.yaml").read_text()
        assert kind_of(yaml.safe_load(text)) is YamlKind.WORLD, name
    tasks = sorted(SAMPLES.glob("*.task.yaml"))
    assert tasks
    for path in tasks:
        assert kind_of(read_yaml(path, what="task")) is YamlKind.TASK, path


def test_a_table_is_a_table_and_its_loader_takes_it() -> None:
    behaviors = ["avoid", "wander_left", "wander_right"]
    data = {
        "format": "lfdfuse/fusion-table@1",
        "behaviors": behaviors,
        "default_weights": default_weights_for(behaviors),
        "network": {"name": "n", "steps": [{"name": "free", "goal": None, "fusion": []}]},
    }
    assert kind_of(data) is YamlKind.TABLE
    assert parse_table(data).behaviors == tuple(behaviors)


@given(st.dictionaries(keys, values, max_size=6), values)
def test_the_top_level_keys_decide(data: dict[str, object], v: object) -> None:
    """``format`` makes a table whatever else is there; else ``task`` a task; else a world."""
    assert kind_of({**data, "format": v}) is YamlKind.TABLE
    rest = {k: x for k, x in data.items() if k != "format"}
    assert kind_of({**rest, "task": v}) is YamlKind.TASK
    plain = {k: x for k, x in rest.items() if k != "task"}
    assert kind_of(plain) is YamlKind.WORLD


@given(st.none() | st.integers() | st.floats() | st.text() | st.lists(values))
def test_what_is_not_a_mapping_is_none_of_ours(data: object) -> None:
    assert kind_of(data) is None
