"""The library never prints, exits or imports typer/rich; only lfdfuse.cli does."""

from __future__ import annotations

import ast
from pathlib import Path

LIB = Path(__file__).resolve().parents[1] / "lfdfuse"


def _library_files() -> list[Path]:
    """Every library module: all but the CLI and the developer tools (bench, sample logs), which may print."""
    return [
        p
        for p in LIB.rglob("*.py")
        if not {"cli", "tools"} & set(p.relative_to(LIB).parts) and p.name != "__main__.py"
    ]


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
