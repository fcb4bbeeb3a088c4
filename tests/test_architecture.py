"""The library never prints, exits or imports typer/rich; only lfdfuse.cli does. The package is
what a user runs: benchmarks and test support live under tests/, and nothing in lfdfuse/ reaches them."""

from __future__ import annotations

import ast
import functools
from pathlib import Path

LIB = Path(__file__).resolve().parents[1] / "lfdfuse"


def _library_files() -> list[Path]:
    """Every library module: all but the CLI, which prints."""
    return [p for p in LIB.rglob("*.py") if "cli" not in p.relative_to(LIB).parts and p.name != "__main__.py"]


def test_library_does_not_import_the_cli_stack() -> None:
    for path in _library_files():
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            for n in names:
                assert n.split(".")[0] not in ("typer", "rich", "click"), f"{path} imports {n}"
                assert not n.startswith("lfdfuse.cli"), f"{path} imports the CLI"


def _reaches_into_tests(source: str) -> list[str]:
    """The modules under tests/ that ``source`` imports, by statement or by name through importlib."""
    found: list[str] = []
    for node in ast.walk(ast.parse(source)):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names = [node.module]
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            func = node.func
            called = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if called in ("import_module", "__import__") and isinstance(node.args[0].value, str):
                names = [node.args[0].value]
        found += [n for n in names if n.split(".")[0] == "tests"]
    return found


def test_the_tests_import_finder_sees_statements_and_importlib() -> None:
    probe = (
        "import importlib\nfrom tests.support import offroute\nimport testsuite\n"
        "def f():\n    return importlib.import_module('tests.bench.world')\n"
    )
    assert _reaches_into_tests(probe) == ["tests.support", "tests.bench.world"]


def test_package_does_not_reach_into_tests() -> None:
    """tests/ (benchmarks, generated-world experiments, test robots) is not in the wheel: no module
    of lfdfuse/ may import it."""
    bad = [f"{p} imports {n}" for p in LIB.rglob("*.py") for n in _reaches_into_tests(p.read_text())]
    assert not bad, "lfdfuse/ imports tests/:\n  " + "\n  ".join(bad)


def test_no_benchmark_in_the_package() -> None:
    """Benchmarks are developer tools (tests/bench, ``make bench``), not part of what a user installs."""
    assert not sorted(LIB.rglob("bench*.py")), "benchmarks belong in tests/bench"


def test_library_does_not_print_or_exit() -> None:
    for path in _library_files():
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
                assert node.func.id not in ("print", "exit", "quit"), (
                    f"{path}:{node.lineno} calls {node.func.id}"
                )


def test_no_global_numpy_rng() -> None:
    for path in LIB.rglob("*.py"):
        text = path.read_text()
        for bad in (
            "np.random.seed(",
            "np.random.rand(",
            "np.random.normal(",
            "np.random.uniform(",
            "np.random.choice(",
        ):
            assert bad not in text, f"{path} uses the global numpy RNG ({bad})"


def test_only_viz_imports_matplotlib() -> None:
    """Plots live in lfdfuse.viz; the CLI imports it inside the plot and report commands only."""
    for path in LIB.rglob("*.py"):
        parts = path.relative_to(LIB).parts
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            for n in names:
                if n.split(".")[0] == "matplotlib":
                    assert parts[0] == "viz", f"{path} imports {n}"
                if n.startswith("lfdfuse.viz") and parts[0] != "viz":
                    # the CLI imports viz lazily, inside a function, so `lfdfuse --help` stays fast
                    assert parts[0] == "cli" and node.col_offset > 0, f"{path} imports {n} at module level"


# --- the import graph: every import counts (module level, lazy, TYPE_CHECKING) ---------------


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(LIB.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(LIB.rglob("*.py"))}


def _resolve(name: str, modules: dict[str, Path]) -> str | None:
    """The lfdfuse module a dotted name lives in (the longest prefix that is a module)."""
    while name:
        if name in modules:
            return name
        name = name.rpartition(".")[0]
    return None


def _imports_of(module: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """Every lfdfuse module `module` imports, wherever the import statement sits.

    `from pkg import name` counts as an import of `pkg` (its `__init__` runs) and, when `name`
    is itself a module, of `pkg.name` too; relative imports are resolved against `module`.
    """
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            targets = [base] + [f"{base}.{a.name}" for a in node.names]
        for t in targets:
            resolved = _resolve(t, modules)
            if resolved is not None and resolved != module:
                found.add(resolved)
    return found


@functools.cache  # parsed once for both tests
def _import_graph() -> dict[str, set[str]]:
    modules = _modules()
    return {m: _imports_of(m, p, modules) for m, p in modules.items()}


def _strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's algorithm, iterative; components of more than one module (or a self-loop)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work: list[tuple[str, list[str]]] = [(root, sorted(graph[root]))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, todo = work[-1]
            if todo:
                nxt = todo.pop(0)
                if nxt not in index:
                    index[nxt] = low[nxt] = counter
                    counter += 1
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, sorted(graph.get(nxt, ()))))
                elif nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                comp: list[str] = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == node:
                        break
                if len(comp) > 1 or node in graph.get(node, ()):
                    out.append(sorted(comp))
    return out


def _cycle_path(graph: dict[str, set[str]], component: list[str]) -> list[str]:
    """One concrete cycle through the component's first module, as a path a -> b -> ... -> a."""
    members = set(component)
    start = component[0]
    parent: dict[str, str] = {}
    frontier = [start]
    while frontier:
        nxt: list[str] = []
        for node in frontier:
            for dep in sorted(graph[node] & members):
                if dep == start:
                    path = [start]
                    while node != start:
                        path.append(node)
                        node = parent[node]
                    return [start, *reversed(path[1:]), start]
                if dep not in parent:
                    parent[dep] = node
                    nxt.append(dep)
        frontier = nxt
    return component


def test_strongly_connected_finds_a_planted_cycle() -> None:
    """The finder itself: a chain has no cycle; closing it makes one component, reported as a path."""
    chain = {"a": {"b"}, "b": {"c"}, "c": set(), "d": {"a"}}
    assert _strongly_connected(chain) == []
    looped = {**chain, "c": {"a"}}
    comps = _strongly_connected(looped)
    assert comps == [["a", "b", "c"]]
    assert _cycle_path(looped, comps[0]) == ["a", "b", "c", "a"]


def test_import_graph_sees_lazy_and_type_checking_imports(tmp_path: Path) -> None:
    """The walk must see imports inside functions and under `if TYPE_CHECKING:`, relative ones too."""
    modules = {"lfdfuse.p": LIB, "lfdfuse.p.a": LIB, "lfdfuse.p.b": LIB, "lfdfuse.q": LIB}
    src = (
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from lfdfuse.q import Thing\n"
        "def f():\n    from .b import g\n    return g\n"
    )
    package_probe = "def h():\n    from . import b\n    return b\n"
    probe = tmp_path / "a.py"
    probe.write_text(src)
    found = _imports_of("lfdfuse.p.a", probe, modules)
    assert found == {"lfdfuse.q", "lfdfuse.p.b"}
    probe.write_text(package_probe)
    # `from . import b` runs the package's __init__ first: it counts as importing the package too
    assert _imports_of("lfdfuse.p.a", probe, modules) == {"lfdfuse.p", "lfdfuse.p.b"}


def test_no_import_cycles() -> None:
    """Zero cycles inside lfdfuse/, counting lazy imports, TYPE_CHECKING imports and package re-exports.

    A lazy import is a cycle in disguise (STYLE, lessons): move the shared thing below both.
    """
    graph = _import_graph()
    cycles = [" -> ".join(_cycle_path(graph, c)) for c in _strongly_connected(graph)]
    assert not cycles, "import cycles in lfdfuse/:\n  " + "\n  ".join(cycles)


def test_viz_imports_no_stage() -> None:
    """viz/ draws from data it is handed: it imports no stage that produces the data."""
    stages = ("lfdfuse.segment", "lfdfuse.estimate", "lfdfuse.execute", "lfdfuse.sources")
    graph = _import_graph()
    bad = sorted(
        f"{m} imports {dep}"
        for m, deps in graph.items()
        if m.startswith("lfdfuse.viz")
        for dep in deps
        if any(dep == s or dep.startswith(s + ".") for s in stages)
    )
    assert not bad, "viz/ imports stages:\n  " + "\n  ".join(bad)


# --- the floors: every arrow between stages points down ----------------------------------------

#: the stages of lfdfuse/ (top-level modules and subpackages), bottom floor first (DESIGN §14).
#: A stage imports only stages on lower floors; stages on one floor know nothing of each other.
LAYERS: tuple[tuple[str, ...], ...] = (
    (
        "lfdfuse",
        "errors",
        "progress",
        "words",
        "kernels",
    ),  # the package root (its version), the error hierarchy, kernels and numpy's sum in them
    ("files", "validate", "parallel"),
    ("robot", "control"),  # the types every stage shares and the ROS conversion; vector ↔ command
    ("world",),
    ("sim",),
    ("behaviors",),
    ("log",),
    ("network",),
    ("sources",),
    ("segment",),
    ("estimate",),
    ("execute",),
    ("drive", "learn"),
    ("record",),  # a live robot (drive's transports) written as import writes a demo
    ("evaluate",),
    ("viz",),
    ("cli",),
    ("__main__",),
)


def _stage(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def test_every_stage_sits_on_one_floor() -> None:
    floors = [s for floor in LAYERS for s in floor]
    assert len(floors) == len(set(floors)), "a stage on two floors"
    unplaced = sorted({_stage(m) for m in _import_graph()} - set(floors))
    assert not unplaced, f"stages on no floor of LAYERS (place them): {unplaced}"


def test_no_upward_or_sideways_arrows() -> None:
    """Data flows one way: a stage imports only stages on lower floors."""
    floor = {s: i for i, stages in enumerate(LAYERS) for s in stages}
    bad = sorted(
        f"{m} imports {dep}"
        for m, deps in _import_graph().items()
        for dep in deps
        if _stage(m) != _stage(dep) and floor.get(_stage(dep), 0) >= floor.get(_stage(m), 0)
    )
    assert not bad, "arrows that do not point down:\n  " + "\n  ".join(bad)


# --- the robot layer: one home for the types every stage shares --------------------------------

#: the shared robot types and conversions, by the robot/ module that defines them
ROBOT_NAMES = {
    "Pose": "lfdfuse.robot.pose",
    "ScanGeometry": "lfdfuse.robot.readings",
    "Detection": "lfdfuse.robot.readings",
    "Reading": "lfdfuse.robot.readings",
    "Observation": "lfdfuse.robot.readings",
    "ScanRecord": "lfdfuse.robot.records",
    "CommandRecord": "lfdfuse.robot.records",
    "PoseRecord": "lfdfuse.robot.records",
    "no_return": "lfdfuse.robot.records",
    "same_geometry": "lfdfuse.robot.records",
    "Mount": "lfdfuse.robot.mount",
    "mount_of": "lfdfuse.robot.mount",
    "base_geometry": "lfdfuse.robot.mount",
    "quaternion_yaw": "lfdfuse.robot.ros",
    "quaternion_matrix": "lfdfuse.robot.ros",
    "transform_matrix": "lfdfuse.robot.ros",
    "laser_mount": "lfdfuse.robot.ros",
    "stated_limits": "lfdfuse.robot.limits",
}


def test_the_robot_layer_sits_on_the_error_hierarchy_alone() -> None:
    bad = sorted(
        f"{m} imports {dep}"
        for m, deps in _import_graph().items()
        if _stage(m) == "robot"
        for dep in deps
        if _stage(dep) not in ("robot", "errors")
    )
    assert not bad, "robot/ must not know a stage:\n  " + "\n  ".join(bad)


def test_shared_robot_types_live_in_robot_alone() -> None:
    """Each is defined once, in robot/, and imported from there: not from the simulator or an
    importer that happens to use it (no re-export), and no second copy elsewhere."""
    here, used = [], []
    for path in sorted(LIB.rglob("*.py")):
        module = _module_name(path)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef | ast.FunctionDef) and node.name in ROBOT_NAMES:
                if ROBOT_NAMES[node.name] != module:
                    here.append(f"{module} defines {node.name}")
            if (
                isinstance(node, ast.ImportFrom)
                and node.level == 0
                and (node.module or "").startswith("lfdfuse")
            ):
                for a in node.names:
                    if a.name in ROBOT_NAMES and node.module != ROBOT_NAMES[a.name]:
                        used.append(f"{module} imports {a.name} from {node.module}")
    assert not here, "robot types defined outside robot/:\n  " + "\n  ".join(here)
    assert not used, "robot types imported from another stage:\n  " + "\n  ".join(used)


def test_stages_reach_robot_types_without_another_stages_internals() -> None:
    """behaviors reads scans without the simulator; drive reads the wire without the importers;
    the importers and the simulator know nothing of each other."""
    forbidden = {
        "behaviors": ("lfdfuse.sim",),
        "drive": ("lfdfuse.sources.importers", "lfdfuse.sim.simulator"),
        "sim": ("lfdfuse.sources",),
        "sources.importers": ("lfdfuse.sim", "lfdfuse.drive"),
    }
    bad = []
    for m, deps in _import_graph().items():
        for who, banned in forbidden.items():
            if m == f"lfdfuse.{who}" or m.startswith(f"lfdfuse.{who}."):
                bad += [
                    f"{m} imports {d}" for d in deps if any(d == b or d.startswith(b + ".") for b in banned)
                ]
    assert not bad, "\n  ".join(bad)


#: the only modules that may import ``cyclonedds`` (the --ros2 path; the default path never loads it)
DDS_MODULES = {"lfdfuse.robot.idl", "lfdfuse.drive.ros2.names", "lfdfuse.drive.ros2.client"}


def test_only_the_ros2_transport_imports_cyclonedds() -> None:
    found = set()
    for path in sorted(LIB.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else []
            )
            if any(n == "cyclonedds" or n.startswith("cyclonedds.") for n in names):
                found.add(_module_name(path))
    assert found == DDS_MODULES, f"cyclonedds imported by {sorted(found - DDS_MODULES)}"


#: a module past this many lines has taken on a second or third job: split it
MAX_MODULE_LINES = 500


def test_no_module_over_its_budget() -> None:
    long = sorted(
        f"{p.relative_to(LIB.parent)}: {n} lines"
        for p in LIB.rglob("*.py")
        if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES
    )
    assert not long, f"modules over {MAX_MODULE_LINES} lines (split them): {long}"
