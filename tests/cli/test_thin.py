"""The CLI parses, calls the library, renders (STYLE habit 2): it computes nothing itself."""

from __future__ import annotations

import ast
from pathlib import Path

CLI = Path(__file__).resolve().parents[2] / "lfdfuse" / "cli"
#: teleop's live view keeps the drawn trail as an array for the map renderer
NUMPY_OK = {"teleop.py"}


def _imports(path: Path) -> set[str]:
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
    return out


def test_no_command_does_arithmetic_or_parses_files_itself() -> None:
    files = sorted(CLI.glob("*.py"))
    assert len(files) > 10
    for path in files:
        mods = {m.split(".")[0] for m in _imports(path)}
        assert not mods & {"yaml", "orjson"}, f"{path.name} parses a file itself"
        if path.name not in NUMPY_OK:
            assert not mods & {"numpy", "scipy"}, f"{path.name} computes (imports numpy/scipy)"


def test_no_command_checks_a_range_by_hand() -> None:
    """Ranges are typer's (``min=``/``max=``): no ``raise`` after a comparison in a command body."""
    for path in sorted(CLI.glob("*.py")):
        if path.name in ("common.py",):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.If) and isinstance(node.test, ast.Compare):
                raises = [n for n in node.body if isinstance(n, ast.Raise)]
                ops = {type(o) for o in node.test.ops}
                numeric = ops & {ast.Lt, ast.LtE, ast.Gt, ast.GtE}
                assert not (raises and numeric), f"{path.name}:{node.lineno} checks a range by hand"
