"""The behaviour catalogue is the one list of behaviours: every other list agrees with it.

A behaviour without an acronym, a colour or an entry in the fusion-table schema (both copies)
fails here; so does a Foxglove layout, an abbreviation table, a colour table or ``drive``'s
inputs that disagree with the catalogue.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lfdfuse.behaviors import catalogue, library
from lfdfuse.behaviors.names import ABBREVIATIONS, abbreviation
from lfdfuse.behaviors.primitives import (
    BASE_BEHAVIORS,
    PRESETS,
    BehaviorParams,
    BehaviorState,
    Observations,
    compute,
)
from lfdfuse.behaviors.spec import BehaviorSpec
from lfdfuse.drive.core import Inputs, missing_input
from lfdfuse.execute.record import LfdRecorder
from lfdfuse.network.stepper import NetworkStepper
from lfdfuse.network.table import default_weights_for, parse_table
from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Observation, Reading, ScanGeometry
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.viz import colors
from lfdfuse.world.model import load_world
from tests.conftest import ROOT

SCHEMAS = (
    ROOT / "schemas" / "fusion-table.schema.json",
    ROOT / "lfdfuse" / "schemas" / "fusion-table.schema.json",
)
HEX = re.compile(r"#[0-9A-Fa-f]{6}")


def _schema_pattern(path: Path) -> str:
    schema = json.loads(path.read_text())
    return str(schema["properties"]["behaviors"]["items"]["pattern"])


def problems(specs: Sequence[BehaviorSpec], schema_pattern: str) -> list[str]:
    """What is missing from the specs: an acronym, a colour, a schema entry, a unique name."""
    out: list[str] = []
    acronyms = [s.acronym for s in specs]
    for s in specs:
        example = s.name + "x" if s.family else s.name
        if not s.acronym:
            out.append(f"{s.name}: no acronym")
        elif acronyms.count(s.acronym) > 1:
            out.append(f"{s.name}: acronym {s.acronym} shared")
        if not s.family and not HEX.fullmatch(s.color):
            out.append(f"{s.name}: no colour")
        if re.fullmatch(schema_pattern, example) is None:
            out.append(f"{s.name}: not in the fusion-table schema")
        if not s.inputs:
            out.append(f"{s.name}: no inputs")
    names = [s.name for s in specs]
    out.extend(f"{n}: named twice" for n in sorted({n for n in names if names.count(n) > 1}))
    return out


@pytest.mark.parametrize("schema", SCHEMAS, ids=["schemas", "packaged"])
def test_every_behaviour_has_an_acronym_a_colour_and_a_schema_entry(schema: Path) -> None:
    assert problems(catalogue.CATALOGUE, _schema_pattern(schema)) == []


def test_the_schema_lists_exactly_the_catalogue() -> None:
    """Both copies of the schema hold the catalogue's name pattern (regenerate with name_pattern())."""
    for schema in SCHEMAS:
        assert _schema_pattern(schema) == catalogue.name_pattern(), schema


def test_the_check_fails_on_a_behaviour_lacking_a_colour_an_acronym_or_a_schema_entry() -> None:
    pattern = catalogue.name_pattern()
    base = catalogue.CATALOGUE[0]
    new = replace(base, name="brand_new", acronym="BN", rank=999)
    assert problems([*catalogue.CATALOGUE, new], pattern) == ["brand_new: not in the fusion-table schema"]
    wider = pattern.replace("^(", "^(brand_new|")
    assert problems([*catalogue.CATALOGUE, new], wider) == []
    assert problems([*catalogue.CATALOGUE, replace(new, color="")], wider) == ["brand_new: no colour"]
    assert problems([*catalogue.CATALOGUE, replace(new, acronym="")], wider) == ["brand_new: no acronym"]
    assert problems([*catalogue.CATALOGUE, replace(new, acronym="LA")], wider) == [
        "avoid: acronym LA shared",
        "brand_new: acronym LA shared",
    ]


def test_the_catalogue_is_every_module_of_the_library() -> None:
    import importlib
    import pkgutil

    gathered = []
    for info in pkgutil.iter_modules(library.__path__):
        module = importlib.import_module(f"{library.__name__}.{info.name}")
        assert getattr(module, "SPECS", ()), f"{module.__name__} holds no SPECS"
        gathered.extend(module.SPECS)
    assert sorted(s.name for s in gathered) == sorted(s.name for s in catalogue.CATALOGUE)
    assert [s.rank for s in catalogue.CATALOGUE] == sorted(s.rank for s in catalogue.CATALOGUE)


def test_names_colours_and_inputs_come_from_the_catalogue() -> None:
    for name in BASE_BEHAVIORS:
        spec = catalogue.spec_of(name)
        assert spec is not None
        assert ABBREVIATIONS[name] == abbreviation(name) == spec.acronym
        assert colors.behavior_color(name) == spec.color != colors.UNKNOWN_COLOR
        assert colors.behavior_hatch(name) == spec.hatch
    assert abbreviation("attract_red") == "red"
    assert colors.behavior_color("attract_red") == colors.target_color("red")
    assert colors.behavior_color("nonsense") == colors.UNKNOWN_COLOR
    # drive: a robot without camera or sonar lacks exactly the behaviours needing them
    bare, full = Inputs(), Inputs(camera=True, sonar=True)
    lacking = {n: missing_input(n, bare) for n in [*BASE_BEHAVIORS, "attract_red"] if missing_input(n, bare)}
    assert lacking == {"sonar_avoid": "sonar", "attract_red": "camera"}
    assert all(missing_input(n, full) == "" for n in [*BASE_BEHAVIORS, "attract_red"])


def test_default_weights_are_the_catalogue_roles() -> None:
    """avoid 1, sonar_avoid 0.5, the wanderers share 1 (in this key order: tables are written so)."""
    got = default_weights_for(("attract_red", "wander_right", "sonar_avoid", "wander_left", "avoid"))
    assert list(got.items()) == [
        ("avoid", 1.0),
        ("sonar_avoid", 0.5),
        ("wander_left", 0.5),
        ("wander_right", 0.5),
    ]
    assert default_weights_for(("wander", "wander_left", "wander_right"))["wander"] == 0.3333
    assert default_weights_for(("wall_attract", "attract_red")) == {"wall_attract": 1.0, "attract_red": 1.0}


def test_the_run_layout_plots_every_weight_in_its_colour() -> None:
    layout = json.loads((ROOT / "lfdfuse" / "foxglove" / "run-layout.json").read_text())
    series = {p["label"]: p for p in layout["configById"]["Plot!lfdfuse-weights"]["paths"]}
    targets = load_world("building").target_names
    want = [*BASE_BEHAVIORS, *(f"attract_{t}" for t in targets)]
    assert sorted(series) == sorted(want)
    for name in want:
        assert series[name]["value"] == f"/lfd/fused.weights.{name}"
        assert series[name]["color"].lower() == catalogue.color(name).lower(), name


class _Log:
    """A log writer that keeps what the recorder writes to ``/lfd/overlay``."""

    def __init__(self) -> None:
        self.scenes: list[dict[str, Any]] = []

    def add_topic(self, *_: object) -> None:
        pass

    def write_raw(self, topic: str, _t: int, data: bytes) -> None:
        if topic == "/lfd/overlay":
            self.scenes.append(json.loads(data))

    def write_tick(self, t: int, messages: list[tuple[str, bytes]]) -> None:
        for topic, data in messages:
            self.write_raw(topic, t, data)

    def write(self, topic: str, _t: int, scene: dict[str, Any]) -> None:
        if topic == "/lfd/overlay":
            self.scenes.append(scene)


def test_overlay_arrows_take_the_catalogue_colours() -> None:
    """``/lfd/overlay``: each behaviour's arrow in its catalogue colour, whatever its column."""
    names = ["wall_attract_left", "avoid", "wander"]  # not the catalogue's order
    table = parse_table(
        {
            "format": "lfdfuse/fusion-table@1",
            "behaviors": names,
            "default_weights": {n: 1.0 for n in names},
            "network": {"name": "n", "steps": [{"name": "free", "goal": None, "fusion": []}]},
        }
    )
    geom = ScanGeometry(-np.pi / 2, np.pi / 180, 181, 8.0)
    stepper = NetworkStepper(
        table=table,
        world=None,
        sensors=SensorParams(),
        rng=np.random.default_rng(0),
        geometry=geom,
        safety=None,
    )
    log = _Log()
    recorder = LfdRecorder(log, stepper)  # type: ignore[arg-type]
    ranges = np.full(181, 5.0)
    ranges[150:181] = 1.0  # a wall near on the left: all three behaviours apply
    obs = Observation(0, 0, Pose(0.0, 0.0, 0.0), Reading(ranges, np.zeros(0), ()))
    recorder.record(obs, stepper.command(obs))
    arrows = log.scenes[0]["entities"][0]["arrows"]
    got = [(a["color"]["r"], a["color"]["g"], a["color"]["b"]) for a in arrows]
    want = [catalogue.rgb(n) for n in names] + [(1.0, 1.0, 1.0)]  # the fused vector in white
    assert np.allclose(got, want), (got, want)
    assert len(set(want)) == len(want)


def test_presets_name_catalogue_behaviours() -> None:
    for preset in PRESETS.values():
        assert all(n == "attract" or catalogue.spec_of(n) is not None for n in preset)


def test_a_state_is_for_one_behaviour_set() -> None:
    geom = ScanGeometry(-np.pi / 2, np.pi / 180, 181, 8.0)
    obs = Observations.from_detections(
        ranges_m=np.full((2, 181), 3.0), geometry=geom, detections=[[], []], target_names=[]
    )
    state = BehaviorState(["avoid"], BehaviorParams())
    with pytest.raises(Exception, match="another behaviour set"):
        compute(obs, ["avoid", "wander"], BehaviorParams(), state)


def test_a_primitive_that_reads_the_pose_says_it_reads_odometry() -> None:
    """A live tick carries the pose only to a behaviour set with an ``odometry`` input (the
    stepper leaves it out otherwise): every library module whose primitives read it declares it."""
    import importlib
    import pkgutil

    import lfdfuse.behaviors.library as library

    readers = 0
    for info in pkgutil.iter_modules(library.__path__):
        module = importlib.import_module(f"{library.__name__}.{info.name}")
        source = Path(module.__file__ or "").read_text()
        if ".pose" in source:
            readers += 1
            assert all("odometry" in spec.inputs for spec in module.SPECS), info.name
    assert readers >= 1  # follow
