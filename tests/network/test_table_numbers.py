"""Fusion tables at the boundary: every number of a table is read through the shared
validator (type before arithmetic, finite, in range); a weighted attract behaviour needs its
target in the world (DESIGN §8), an unweighted one does not."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import pytest
import yaml

from lfdfuse.errors import ConfigError
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.network.table import dump_table, parse_table
from lfdfuse.world.model import load_world

TABLE: dict[str, Any] = {
    "format": "lfdfuse/fusion-table@1",
    "behaviors": ["avoid", "wander_left", "wander_right"],
    "default_weights": {"avoid": 0.4, "wander_left": 0.3, "wander_right": 0.3},
    "network": {
        "name": "n",
        "steps": [
            {
                "name": "s",
                "goal": None,
                "default_weights": {"avoid": 1.0},
                "fusion": [
                    {
                        "bac": 7,
                        "weights": {"avoid": 0.2, "wander_left": 0.8},
                        "std": {"avoid": 0.1},
                        "trial_std": {"avoid": 0.05},
                        "samples": 12,
                        "fit_error_deg": 4.5,
                        "low_samples": False,
                    }
                ],
            }
        ],
    },
}

ROW = ("network", "steps", 0, "fusion", 0)
#: every number of TABLE, with its field name as the error names it
NUMBER_FIELDS: list[tuple[tuple[Any, ...], str]] = [
    (("default_weights", "avoid"), "default_weights.avoid"),
    (("network", "steps", 0, "default_weights", "avoid"), "default_weights.avoid"),
    ((*ROW, "weights", "avoid"), "weights.avoid"),
    ((*ROW, "std", "avoid"), "std.avoid"),
    ((*ROW, "trial_std", "avoid"), "trial_std.avoid"),
    ((*ROW, "fit_error_deg"), "fit_error_deg"),
]
INT_FIELDS: list[tuple[tuple[Any, ...], str]] = [((*ROW, "bac"), "bac"), ((*ROW, "samples"), "samples")]
NOT_NUMBERS: list[Any] = [10**330, 10**400, math.nan, math.inf, "1.5", "lots", True, None, [1], {"a": 1}]


def _with(path: tuple[Any, ...], value: Any) -> dict[str, Any]:
    data = copy.deepcopy(TABLE)
    node: Any = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return data


def test_the_base_table_round_trips() -> None:
    table = parse_table(copy.deepcopy(TABLE))
    assert parse_table(yaml.safe_load(dump_table(table))) == table


@pytest.mark.parametrize(("path", "field"), NUMBER_FIELDS, ids=lambda x: str(x))
@pytest.mark.parametrize("bad", NOT_NUMBERS, ids=repr)
def test_a_number_that_is_not_a_finite_float_is_a_config_error_naming_its_field(
    path: tuple[Any, ...], field: str, bad: Any
) -> None:
    if bad is None and field in ("std.avoid", "trial_std.avoid", "fit_error_deg"):
        pytest.skip("null means absent for these optional fields")
    with pytest.raises(ConfigError) as info:
        parse_table(_with(path, bad))
    message = str(info.value)
    assert field in message and "\n" not in message and len(message) < 300


@pytest.mark.parametrize(("path", "field"), INT_FIELDS, ids=lambda x: str(x))
@pytest.mark.parametrize("bad", [-1, 1.5, "3", True, math.nan, 10**400], ids=repr)
def test_an_integer_field_refuses_what_is_not_a_non_negative_integer(
    path: tuple[Any, ...], field: str, bad: Any
) -> None:
    with pytest.raises(ConfigError, match=field):
        parse_table(_with(path, bad))


def test_a_large_sample_count_is_kept_up_to_int64() -> None:
    """A count of steps fits int64 (the arrays it counts); up to there it survives the round trip."""
    with pytest.raises(ConfigError, match="samples"):
        parse_table(_with((*ROW, "samples"), 2**63))
    table = parse_table(_with((*ROW, "samples"), 2**63 - 1))
    assert table.network.steps[0].fusion[0].samples == 2**63 - 1
    assert parse_table(yaml.safe_load(dump_table(table))) == table


def test_low_samples_must_be_a_boolean() -> None:
    with pytest.raises(ConfigError, match="low_samples"):
        parse_table(_with((*ROW, "low_samples"), "maybe"))


# --- weighted targets (DESIGN §8), at execute -----------------------------------------------


def _attract(weights: dict[str, float]) -> dict[str, Any]:
    data = copy.deepcopy(TABLE)
    data["behaviors"] = ["avoid", "wander_left", "attract_purple"]
    data["default_weights"] = {"avoid": 0.4, "wander_left": 0.6}
    data["network"]["steps"][0] = {"name": "s", "goal": None, "fusion": [{"bac": 7, "weights": weights}]}
    return data


def test_execute_refuses_a_weighted_target_the_world_lacks_before_writing(tmp_path: Path) -> None:
    table = parse_table(_attract({"avoid": 0.3, "attract_purple": 0.7}))
    out = tmp_path / "r.mcap"
    with pytest.raises(ConfigError, match="purple"):
        run_table(
            ExecuteOptions(world=load_world("corridor"), table=table, max_time_s=0.5), out=out, command="t"
        )
    assert not out.exists() and not list(tmp_path.iterdir())


def test_execute_runs_a_table_whose_target_carries_no_weight(tmp_path: Path) -> None:
    table = parse_table(_attract({"avoid": 0.3, "wander_left": 0.7, "attract_purple": 0.0}))
    out = tmp_path / "r.mcap"
    res = run_table(
        ExecuteOptions(world=load_world("corridor"), table=table, max_time_s=0.5), out=out, command="t"
    )
    assert out.exists() and res.summary is not None
