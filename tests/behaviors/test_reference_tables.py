"""The behaviour catalogue changes no table: the existing behaviours learn byte-identical tables.

Each case below is a short demonstration (simulate → segment → estimate, fixed seeds) whose
table was learned once and saved under ``reference/``; the test learns it again with the code
of today and compares the bytes. Together the cases compute every behaviour of the catalogue
that existed before ``follow`` (the keep-left set of ``make demo``, the three-goal task's
attractors with the default preset, and the ``full`` preset for ``wall_side_*`` and
``circular_avoid_*``).

To write the references again (only when a table is *meant* to change):
``python -m tests.behaviors.test_reference_tables``.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app

REFERENCE = Path(__file__).parent / "reference"
TASK = Path(__file__).resolve().parents[2] / "sample_logs" / "three-goals.task.yaml"


@dataclass(frozen=True)
class Case:
    """One reference table: the commands that learn it."""

    name: str
    simulate: tuple[str, ...]
    segment: tuple[str, ...]
    estimate: tuple[str, ...] = ()


CASES = (
    Case(
        "keep-left",
        ("--teacher", "keep-left", "--duration", "60", "--seed", "1"),
        ("--behaviors", "avoid,wander_left,wander_right,wall_attract_left,wall_attract_right,sonar_avoid"),
    ),
    Case(
        "three-goals",
        ("--teacher", str(TASK), "--duration", "150", "--seed", "1"),
        (),
    ),
    Case(
        "full",
        ("--teacher", "keep-right", "--duration", "60", "--seed", "2"),
        ("--behaviors", "full"),
        ("--seed", "3"),
    ),
)


def _run(args: list[str]) -> None:
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output + repr(res.exception)


def learn(case: Case, work: Path) -> bytes:
    """The table ``case`` learns, as the bytes ``estimate`` writes."""
    demo = work / f"{case.name}.mcap"
    seg = work / f"{case.name}.seg.mcap"
    table = work / f"{case.name}.yaml"
    _run(["simulate", *case.simulate, "-o", str(demo)])
    _run(["segment", str(demo), *case.segment, "-o", str(seg)])
    _run(["estimate", str(seg), *case.estimate, "-o", str(table)])
    return table.read_bytes()


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_tables_are_byte_identical_to_the_reference(case: Case, tmp_path: Path) -> None:
    want = (REFERENCE / f"{case.name}.yaml").read_bytes()
    assert learn(case, tmp_path) == want


def test_the_references_cover_every_behaviour_but_follow() -> None:
    """The cases compute each behaviour that existed before ``follow`` (the full preset names them)."""
    import yaml

    seen = set()
    for case in CASES:
        seen.update(yaml.safe_load((REFERENCE / f"{case.name}.yaml").read_text())["behaviors"])
    from lfdfuse.behaviors.primitives import BASE_BEHAVIORS

    assert set(BASE_BEHAVIORS) - {"follow"} <= seen
    assert {"attract_red", "attract_green", "attract_blue"} <= seen


if __name__ == "__main__":  # write the references again
    import tempfile

    REFERENCE.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as d:
        for c in CASES:
            (REFERENCE / f"{c.name}.yaml").write_bytes(learn(c, Path(d)))
            sys.stderr.write(f"wrote {REFERENCE / c.name}.yaml\n")
