"""The fusion table: round trips, validation, schema, and estimate on the sample demos."""

from __future__ import annotations

import json
import os
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.errors import ConfigError
from lfdfuse.estimate.pipeline import EstimateOptions, Method, estimate_run
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.learn import LearnOptions, learn
from lfdfuse.network.table import FusionTable, dump_table, load_table, parse_table, write_table
from lfdfuse.segment.read import read_segmented
from tests.conftest import ROOT

runner = CliRunner()
SCHEMA = json.loads((ROOT / "schemas" / "fusion-table.schema.json").read_text())

TABLE = {
    "format": "lfdfuse/fusion-table@1",
    "behaviors": ["avoid", "attract_red", "wander_left", "wander_right"],
    "default_weights": {"avoid": 1.0, "wander_left": 0.5, "wander_right": 0.5},
    "network": {
        "name": "demo",
        "steps": [
            {
                "name": "reach-red",
                "goal": {"target": "red"},
                "default_weights": {"avoid": 0.1, "wander_left": 0.9},
                "fusion": [{"bac": 13, "weights": {"avoid": 0.2, "wander_left": 0.5, "wander_right": 0.3}}],
            },
            {
                "name": "nested",
                "goal": None,
                "network": {"name": "sub", "steps": [{"name": "s", "goal": None, "fusion": []}]},
            },
        ],
    },
}


def _mutate(path: list[object], value: object) -> dict:  # type: ignore[type-arg]
    data = json.loads(json.dumps(TABLE))
    node = data
    for key in path[:-1]:
        node = node[key]
    if value is KeyError:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data  # type: ignore[no-any-return]


def test_round_trip_and_schema() -> None:
    t = parse_table(TABLE)
    text = dump_table(t)
    assert parse_table(yaml.safe_load(text)) == t
    jsonschema.validate(yaml.safe_load(text), SCHEMA)
    assert t.targets() == ["red"]


def test_what_the_data_supports_round_trips_and_old_rows_still_load() -> None:
    data = json.loads(json.dumps(TABLE))
    row = data["network"]["steps"][0]["fusion"][0]
    t_old = parse_table(data)  # a row without std, trial_std, samples, identifiable
    assert t_old.network.steps[0].fusion[0].identifiable is None
    assert t_old.network.steps[0].fusion[0].trial_std is None
    assert "identifiable" not in dump_table(t_old) and "trial_std" not in dump_table(t_old)
    row |= {
        "std": {"avoid": 0.01, "wander_left": 0.02, "wander_right": 0.03},
        "trial_std": {"avoid": 0.001, "wander_left": 0.002, "wander_right": 0.003},
        "samples": 412,
        "identifiable": False,
    }
    t = parse_table(data)
    r = t.network.steps[0].fusion[0]
    assert r.identifiable is False and r.trial_std == {
        "avoid": 0.001,
        "wander_left": 0.002,
        "wander_right": 0.003,
    }
    text = dump_table(t)
    assert parse_table(yaml.safe_load(text)) == t
    jsonschema.validate(yaml.safe_load(text), SCHEMA)


def test_both_copies_of_the_schema_are_identical() -> None:
    packaged = ROOT / "lfdfuse" / "schemas" / "fusion-table.schema.json"
    assert json.loads(packaged.read_text()) == SCHEMA


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (["behaviors", 1], "attract", "unknown behaviour 'attract'"),
        (["network", "steps", 0, "fusion", 0, "weights", "avoid"], -0.1, "negative weight"),
        (["network", "steps", 0, "fusion", 0, "weights", "fly"], 0.1, "unknown behaviour 'fly'"),
        (["network", "steps", 0, "fusion", 0, "bac"], KeyError, "missing field 'bac'"),
        (["default_weights"], KeyError, "missing field 'default_weights'"),
        (["network", "steps", 0, "fusion", 0, "weights", "attract_red"], 0.3, "not applicable in BAC 13"),
        (["format"], "other@2", "format must be"),
        (["network", "steps", 0, "speed"], 1, "unknown field 'speed'"),
        (["network", "steps", 0, "default_weights", "avoid"], -1.0, "negative weight"),
        (["network", "steps", 0, "fusion", 0, "identifiable"], "yes", "identifiable must be true or false"),
        (["network", "steps", 0, "fusion", 0, "trial_std"], {"avoid": -0.1}, "negative weight"),
    ],
)
def test_invalid_tables_are_rejected(path: list[object], value: object, message: str) -> None:
    bad = _mutate(path, value)
    with pytest.raises(ConfigError, match=message):
        parse_table(bad)


@pytest.fixture()
def segmented(three_goal_segmented: Path) -> Path:
    return three_goal_segmented


@pytest.mark.parametrize("method", list(Method))
def test_estimate_on_the_sample_demo(segmented: Path, tmp_path: Path, method: Method) -> None:
    res = learn([segmented], options=LearnOptions(EstimateOptions(method=method, trials=2)))
    write_table(res.table, tmp_path / "f.yaml")
    loaded = load_table(tmp_path / "f.yaml")
    assert loaded.behaviors == res.table.behaviors
    jsonschema.validate(yaml.safe_load((tmp_path / "f.yaml").read_text()), SCHEMA)
    steps = loaded.network.steps
    assert [s.goal for s in steps[:3]] == ["red", "green", "blue"]
    assert [s.name for s in steps[:3]] == ["reach-red", "reach-green", "reach-blue"]
    for s in steps:
        for row in s.fusion:
            assert row.fit_error_deg is not None and np.isfinite(row.fit_error_deg)
            assert sum(row.weights.values()) == pytest.approx(1.0, abs=1e-3)
            assert row.low_samples == (row.samples is not None and row.samples < 30)
            assert row.trial_std is not None and set(row.trial_std) == set(row.weights)
            assert (row.identifiable is not None) == (method is Method.PF)
    assert res.table.estimated_by["method"] == method.value


def test_styles_show_in_the_learned_weights(three_goal_table: FusionTable) -> None:
    """Keep-left to red, centre to green, keep-right to blue: the wall-attract weights say so.

    The style teacher is not a fusion of the primitives, so its weights are unknown: this checks
    only that each side's weight clearly dominates on its step (2×); that the style is really
    reproduced is checked in closed loop (tests/execute/test_closed_loop.py)."""
    table = three_goal_table  # the default estimate of the sample demo

    def side_weights(step_index: int) -> tuple[float, float]:
        rows = [r for r in table.network.steps[step_index].fusion if r.samples and r.samples >= 100]
        tot = sum(r.samples for r in rows)  # type: ignore[misc]
        left = sum(r.weights.get("wall_attract_left", 0.0) * r.samples for r in rows) / tot  # type: ignore[operator]
        right = sum(r.weights.get("wall_attract_right", 0.0) * r.samples for r in rows) / tot  # type: ignore[operator]
        return left, right

    left, right = side_weights(0)
    assert left > 2 * right
    left, right = side_weights(2)
    assert right > 2 * left


def test_estimate_is_reproducible(segmented: Path, tmp_path: Path) -> None:
    for name in ("a", "b"):
        opts = EstimateOptions(seed=4, trials=2, smc=SMCParams(particles=96))
        write_table(learn([segmented], options=LearnOptions(opts)).table, tmp_path / f"{name}.yaml")
    assert (tmp_path / "a.yaml").read_text() == (tmp_path / "b.yaml").read_text()


def test_estimate_cli(segmented: Path, tmp_path: Path, sample_dir: Path) -> None:
    out = tmp_path / "f.yaml"
    res = runner.invoke(
        app, ["estimate", str(segmented), "-o", str(out), "--trials", "2", "--particles", "200"]
    )
    assert res.exit_code == 0, res.output
    assert "reach-red" in res.output and "fit°" in res.output and out.exists()
    old = os.getcwd()
    os.chdir(tmp_path)
    try:
        before = sorted(os.listdir(tmp_path))
        bad = runner.invoke(app, ["estimate", str(sample_dir / "keep-left-building.mcap"), "-o", "x.yaml"])
        assert bad.exit_code == 1 and "run `lfdfuse segment" in bad.stderr
        bad = runner.invoke(app, ["estimate", str(segmented), "--method", "magic", "-o", "x.yaml"])
        assert bad.exit_code == 2 and "magic" in bad.stderr  # a usage error: typer offers the choices
        bad = runner.invoke(app, ["estimate", str(segmented), "--likelihood", "magic", "-o", "x.yaml"])
        assert bad.exit_code == 2 and "magic" in bad.stderr
        assert sorted(os.listdir(tmp_path)) == before
    finally:
        os.chdir(old)


def test_all_stationary_is_nothing_to_learn(segmented: Path) -> None:
    """A demo without one informative step is an error, not a table of default weights."""
    run = read_segmented(segmented)
    still = type(run)(**{**run.__dict__, "informative": np.zeros_like(run.informative)})
    with pytest.raises(ConfigError, match="nothing to learn"):
        estimate_run(still, opts=EstimateOptions())
