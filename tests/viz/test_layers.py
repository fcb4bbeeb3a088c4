"""The learning path's layering: no import cycle through estimate, evaluate, viz or learn (lazy
and ``TYPE_CHECKING`` imports included), and viz imports no stage (it draws what it is handed)."""

from __future__ import annotations

import ast
from pathlib import Path

LIB = Path(__file__).resolve().parents[2] / "lfdfuse"
#: the rooms whose cycles this test owns (other rooms' are checked where they live)
MINE = ("lfdfuse.estimate", "lfdfuse.evaluate", "lfdfuse.viz", "lfdfuse.learn")
#: viz draws; these are stages
STAGES = ("lfdfuse.segment", "lfdfuse.estimate", "lfdfuse.execute", "lfdfuse.sources")


def _module(path: Path) -> str:
    parts = path.relative_to(LIB.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, modules: set[str], me: str) -> set[str]:
    """Every lfdfuse module ``path`` (module ``me``) imports, anywhere in the file (functions,
    ``TYPE_CHECKING`` blocks)."""
    package = me if path.name == "__init__.py" else me.rsplit(".", 1)[0]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(
                    package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else [])
                )
            names = [base] + [f"{base}.{a.name}" for a in node.names]
        for n in names:
            while n and n not in modules:
                n = n.rpartition(".")[0]
            if n and n != me:
                out.add(n)
    return out


def _graph() -> dict[str, set[str]]:
    files = {_module(p): p for p in LIB.rglob("*.py")}
    return {m: _imports(p, set(files), m) for m, p in files.items()}


def _cycle_through(graph: dict[str, set[str]], start: str) -> list[str] | None:
    """A path start → … → start, if one exists (depth first)."""
    stack, seen = [(start, [start])], set()
    while stack:
        node, path = stack.pop()
        for nxt in graph.get(node, ()):
            if nxt == start:
                return [*path, start]
            if nxt not in seen:
                seen.add(nxt)
                stack.append((nxt, [*path, nxt]))
    return None


def test_no_import_cycle_through_the_learning_path() -> None:
    graph = _graph()
    for m in sorted(graph):
        if m.startswith(MINE) and not m.endswith("__init__"):
            cycle = _cycle_through(graph, m)
            assert cycle is None, " → ".join(cycle)


def test_the_walk_sees_lazy_and_type_checking_imports(tmp_path: Path) -> None:
    src = tmp_path / "m.py"
    src.write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from lfdfuse.viz.report import X\n"
        "def f():\n    import lfdfuse.estimate.subgoals\n"
    )
    got = _imports(src, {"lfdfuse.viz.report", "lfdfuse.estimate.subgoals", "lfdfuse"}, "lfdfuse.m")
    assert got == {"lfdfuse.viz.report", "lfdfuse.estimate.subgoals"}
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _cycle_through(graph, "a") == ["a", "b", "c", "a"] and _cycle_through(graph, "d") is None


def test_viz_imports_no_stage() -> None:
    graph = _graph()
    for m, deps in graph.items():
        if not m.startswith("lfdfuse.viz"):
            continue
        bad = sorted(d for d in deps if d.startswith(STAGES))
        assert not bad, f"{m} imports {bad}"
