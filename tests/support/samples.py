"""Regenerate ``sample_logs/``: small demonstration logs made by code in this repo.

``python -m tests.support.samples sample_logs`` (``make sample-logs``) rewrites every file; same code,
same bytes.
"""

from __future__ import annotations

from pathlib import Path

import typer
import yaml

from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world

#: The paper's first physical scenario: left to goal 1, centre to goal 2, right to goal 3.
THREE_GOALS = [Leg("red", "keep-left"), Leg("green", "keep-center"), Leg("blue", "keep-right")]
#: Goals off the route: green sits in an office off the corridor a left-keeper follows.
OFFICE = [Leg("red", "keep-left"), Leg("green", "keep-left"), Leg("blue", "keep-left")]


def task_yaml(legs: list[Leg]) -> str:
    return yaml.safe_dump(
        {"task": [{"target": leg.target, "style": leg.style} for leg in legs]}, sort_keys=False
    )


def generate(folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "three-goals.task.yaml").write_text(task_yaml(THREE_GOALS))
    (folder / "office-room.task.yaml").write_text(task_yaml(OFFICE))
    building = load_world("building")
    runs = [
        (
            "keep-left-building.mcap",
            SimulateOptions(
                world=building,
                legs=[Leg(None, "keep-left")],
                teacher_name="keep-left",
                duration_s=150.0,
                seed=1,
            ),
        ),
        (
            "three-goals-building.mcap",
            SimulateOptions(
                world=building,
                legs=THREE_GOALS,
                teacher_name="three-goals.task.yaml",
                duration_s=400.0,
                seed=1,
            ),
        ),
        (
            "pass-left-obstacles.mcap",
            SimulateOptions(
                world=load_world("obstacles"),
                legs=[Leg(None, "pass-left")],
                teacher_name="pass-left",
                duration_s=60.0,
                seed=1,
            ),
        ),
    ]
    out = []
    for name, opts in runs:
        simulate(opts, out=folder / name)
        out.append(folder / name)
    return out


def main(folder: Path = typer.Argument(Path("sample_logs"), help="Where to write the sample logs.")) -> None:
    """Regenerate the sample logs (same code, same bytes)."""
    for path in generate(folder):
        typer.echo(path)


if __name__ == "__main__":
    typer.run(main)
