"""World parsing at the boundary: every number is checked for type before any arithmetic,
then for finiteness; the world modules form no cycle and import nothing lazily
(but the map image stack, where a map image is read)."""

from __future__ import annotations

import ast
import copy
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.errors import WorldError
from lfdfuse.files import parse_yaml
from lfdfuse.world import model, occupancy, parse
from lfdfuse.world.parse import parse_world

WORLD: dict[str, Any] = {
    "name": "box",
    "walls": [[[0, 0], [12, 0], [12, 3], [0, 3], [0, 0]]],
    "obstacles": [{"circle": [8.0, 0.6, 0.3]}, {"polygon": [[4, 2], [5, 2], [5, 2.5]]}],
    "targets": [{"name": "red", "position": [11.0, 1.5], "radius": 0.25}],
    "start": [1.0, 1.5, 0.0],
}

#: every number of WORLD, as the path to it
NUMBER_PATHS: list[tuple[Any, ...]] = (
    [("walls", 0, i, j) for i in range(5) for j in range(2)]
    + [("obstacles", 0, "circle", i) for i in range(3)]
    + [("obstacles", 1, "polygon", i, j) for i in range(3) for j in range(2)]
    + [("targets", 0, "position", i) for i in range(2)]
    + [("targets", 0, "radius"), ("start", 0), ("start", 1), ("start", 2)]
)

NOT_NUMBERS: list[Any] = [
    10**330,
    -(10**330),
    10**400,
    math.nan,
    math.inf,
    -math.inf,
    "1.5",
    "x",
    True,
    None,
    [1],
]


def _with(path: tuple[Any, ...], value: Any) -> dict[str, Any]:
    data = copy.deepcopy(WORLD)
    node: Any = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return data


def test_the_base_world_is_valid() -> None:
    world = parse_world(copy.deepcopy(WORLD))
    assert world.start == (1.0, 1.5, 0.0)
    assert all(isinstance(v, float) for v in world.start)


@pytest.mark.parametrize("path", NUMBER_PATHS, ids=lambda p: ".".join(map(str, p)))
@pytest.mark.parametrize("bad", NOT_NUMBERS, ids=repr)
def test_a_number_that_is_not_a_finite_float_is_a_world_error(path: tuple[Any, ...], bad: Any) -> None:
    with pytest.raises(WorldError) as info:
        parse_world(_with(path, bad))
    assert "\n" not in str(info.value)
    assert len(str(info.value)) < 300  # a 400-digit integer is described, not printed


@settings(max_examples=60, deadline=None)
@given(st.integers(min_value=-(10**420), max_value=10**420), st.sampled_from(NUMBER_PATHS))
def test_any_integer_is_either_read_or_refused_as_a_world_error(value: int, path: tuple[Any, ...]) -> None:
    """No integer, however large, escapes as OverflowError (or any other non-LfdError)."""
    try:
        world = parse_world(_with(path, value))
    except WorldError:
        return
    assert world.segments.dtype.kind == "f"


def test_a_huge_integer_in_world_yaml_is_one_error_through_the_loader() -> None:
    text = f"walls: [[[0, 0], [{10**330}, 0], [12, 3], [0, 0]]]\nstart: [1, 1, 0]\n"
    with pytest.raises(WorldError, match="finite number"):
        parse_world(parse_yaml(text, origin="w.yaml", error=WorldError), origin="w.yaml")


def test_map_yaml_numbers_share_the_validator(tmp_path: Path) -> None:
    data = {
        "image": "m.pgm",
        "resolution": 10**330,
        "origin": [0, 0, 0],
        "occupied_thresh": 0.65,
        "free_thresh": 0.2,
    }
    with pytest.raises(WorldError, match="'resolution' must be a number in"):
        occupancy.parse_map_yaml(data, folder=tmp_path, origin="m.yaml")
    data |= {"resolution": 0.05, "origin": [0, 10**400, 0]}
    with pytest.raises(WorldError, match="'origin'"):
        occupancy.parse_map_yaml(data, folder=tmp_path, origin="m.yaml")


# --- the world package's imports ----------------------------------------------------------------

WORLD_DIR = Path(parse.__file__).parent


#: the map image stack: imported where a map image is read, so a command in a built-in or YAML
#: world does not pay for it (about 0.2 s of start-up)
IMAGE_STACK = ("PIL", "scipy", "skimage")


def _imports(path: Path) -> tuple[set[str], list[int]]:
    """``lfdfuse.world`` modules a file imports, and the lines of imports not at module level
    (but for the image stack's)."""
    tree = ast.parse(path.read_text())
    top = {id(n) for n in tree.body}
    found: set[str] = set()
    nested: list[int] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        else:
            continue
        if id(node) not in top and not all(n.split(".")[0] in IMAGE_STACK for n in names):
            nested.append(node.lineno)
        found |= {
            n
            for n in names
            if n.startswith("lfdfuse.world.") and (WORLD_DIR / f"{n.split('.')[2]}.py").exists()
        }
    return {".".join(n.split(".")[:3]) for n in found}, nested


def test_world_modules_import_nothing_lazily_and_form_no_cycle() -> None:
    graph: dict[str, set[str]] = {}
    for path in sorted(WORLD_DIR.glob("*.py")):
        name = f"lfdfuse.world.{path.stem}"
        deps, nested = _imports(path)
        assert not nested, f"{path.name}: imports inside functions or blocks at lines {nested}"
        graph[name] = deps - {name}
    seen: dict[str, int] = {}  # 1: on the current path, 2: done

    def visit(node: str, trail: list[str]) -> None:
        seen[node] = 1
        for dep in graph.get(node, set()):
            assert seen.get(dep) != 1, f"import cycle: {' -> '.join([*trail, node, dep])}"
            if dep not in seen:
                visit(dep, [*trail, node])
        seen[node] = 2

    for node in graph:
        if node not in seen:
            visit(node, [])
    assert "lfdfuse.world.model" not in graph["lfdfuse.world.occupancy"]
    assert "lfdfuse.world.parse" in graph["lfdfuse.world.occupancy"]


def test_a_built_in_world_loads_without_the_image_stack() -> None:
    code = (
        "import sys\nfrom lfdfuse.world.model import load_world\nload_world('building')\n"
        "print(sorted({m.split('.')[0] for m in sys.modules} & {'PIL', 'scipy', 'skimage'}))"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0 and res.stdout.strip() == "[]", res.stdout + res.stderr


def test_the_loader_re_exports_the_world_it_parses() -> None:
    assert model.World is parse.World and model.parse_world is parse.parse_world
    assert isinstance(model.load_world("corridor"), parse.World)
