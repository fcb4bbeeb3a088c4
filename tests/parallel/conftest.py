from __future__ import annotations

from pathlib import Path

import pytest

from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg, parse_style
from lfdfuse.world.model import load_world
from tests.conftest import ROOT

CORRIDOR_TABLE = ROOT / "lfdfuse" / "evaluate" / "truths" / "corridor-center.yaml"


@pytest.fixture(scope="session")
def short_demos(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Two 30 s demos in the corridor (raw: evaluate segments them on the way)."""
    folder = tmp_path_factory.mktemp("demos")
    out = []
    for k, style in enumerate(("keep-left", "keep-right")):
        path = folder / f"{style}.mcap"
        simulate(
            SimulateOptions(
                world=load_world("corridor"),
                legs=[Leg(None, parse_style(style))],
                teacher_name=style,
                duration_s=30.0,
                seed=k,
            ),
            out=path,
        )
        out.append(path)
    return out


GOAL_TABLE = """format: lfdfuse/fusion-table@1
behaviors: [avoid, attract_red, wander]
default_weights: {avoid: 0.3, wander: 0.7}
network:
  name: to-red
  steps:
    - name: reach-red
      goal: {target: red}
      fusion:
        - bac: 7
          weights: {avoid: 0.2, attract_red: 0.8}
        - bac: 6
          weights: {attract_red: 1.0}
"""


@pytest.fixture()
def goal_table(tmp_path: Path) -> Path:
    path = tmp_path / "to-red.yaml"
    path.write_text(GOAL_TABLE)
    return path
