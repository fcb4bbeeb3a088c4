from __future__ import annotations

from pathlib import Path

import pytest

from lfdfuse.errors import WorldError
from lfdfuse.world import build
from lfdfuse.world.model import builtin_names, load_world


def test_builtin_worlds_are_the_generated_ones() -> None:
    assert builtin_names() == sorted(build.WORLDS)
    folder = Path(build.__file__).parent / "builtin"
    for name in build.WORLDS:
        assert (folder / f"{name}.yaml").read_text() == build.render(name), (
            f"run python -m lfdfuse.world.build ({name})"
        )


@pytest.mark.parametrize("name", ["corridor", "tee", "building", "obstacles"])
def test_builtin_world_loads(name: str) -> None:
    w = load_world(name)
    assert w.name == name and len(w.segments) >= 4 and w.description
    assert w.clearance(w.start[0], w.start[1]) > 0.25


def test_building_has_three_targets() -> None:
    assert load_world("building").target_names == ["red", "green", "blue"]


def _write(tmp_path: Path, text: str) -> str:
    p = tmp_path / "w.yaml"
    p.write_text(text)
    return str(p)


GOOD = "walls:\n  - [[0, 0], [10, 0], [10, 5], [0, 5], [0, 0]]\nstart: [1, 1, 0]\n"


def test_user_world_file(tmp_path: Path) -> None:
    w = load_world(
        _write(
            tmp_path,
            GOOD + "obstacles:\n  - {circle: [5, 2.5, 0.3]}\n  - {polygon: [[7, 1], [8, 1], [8, 2]]}\n",
        )
    )
    assert w.name == "w" and len(w.obstacles) == 2


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (GOOD + "colour: red\n", "unknown key 'colour'"),
        ("walls: [[[0, 0], [1, 1]]\nstart: [", "malformed YAML"),
        ("walls:\n  - [[0, 0], [10, 0], [10, 5], [0, 5], [0, 0]]\nstart: [0.1, 0.1, 0]\n", "start pose"),
        (GOOD + "obstacles:\n  - {polygon: [[1, 1], [3, 3], [3, 1], [1, 3]]}\n", "self-intersecting"),
        ("start: [1, 1, 0]\n", "missing key 'walls'"),
        (GOOD + "targets:\n  - {name: red, position: [1, 1], size: 2}\n", "unknown key 'size'"),
        ("walls:\n  - [[0, 0], [x, 0]]\nstart: [1, 1, 0]\n", "finite number"),
    ],
)
def test_bad_world_files_name_the_problem(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(WorldError, match=message):
        load_world(_write(tmp_path, text))


def test_unknown_world_lists_valid_names() -> None:
    with pytest.raises(
        WorldError, match="building, corridor, obstacles, office-room, ring-spur, ring-spur-large, tee"
    ):
        load_world("nowhere")
