"""``make bench``: every benchmark suite, a summary per suite that fits the terminal, and one
JSON file with every column.

Suites: ``pipeline`` (each stage's speed beside a baseline measured in the same run),
``world`` (raycasting on large maps, simulation on real building maps) and ``estimate``
(round-trip quality against hand-written truth tables, and the cost of estimating). Ratios to
an in-run baseline are what to compare across machines.

    python -m tests.bench.run --out build/bench.json [--suite world] [--quick]
"""

from __future__ import annotations

import importlib
import json
import math
import tempfile
import time
from pathlib import Path
from typing import Any, Literal

import typer
from rich.console import Console
from rich.table import Table

SUITES = {
    "pipeline": "tests.bench.pipeline",
    "world": "tests.bench.world",
    "estimate": "tests.bench.estimate",
    "offroute": "tests.bench.offroute",
    "generated": "tests.bench.generated",
    "corrections": "tests.bench.corrections",
    "memory": "tests.bench.memory",
    "drive": "tests.bench.drive",
    "keys": "tests.bench.keys",
    "parallel": "tests.bench.parallel",
}

app = typer.Typer(add_completion=False, pretty_exceptions_enable=False)


def _cell(value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return " ".join(_cell(v) for v in value)
    if isinstance(value, float):
        if math.isinf(value) or math.isnan(value):
            return "-"
        return f"{value:.3g}" if abs(value) < 100 else f"{value:,.0f}"
    return "" if value is None else str(value)


def render(console: Console, title: str, rows: list[dict[str, Any]]) -> None:
    """A suite's rows as a summary that fits the console: ``name`` and then as many columns, in
    order, as fit whole (no cell is cut); the rest are named below it and kept in the JSON."""
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    cells = {c: [_cell(row.get(c)) for row in rows] for c in columns}
    need = {c: max([len(c), *(len(v) for v in cells[c])]) + 2 for c in columns}  # + padding
    first = [c for c in columns if c == "name"] or columns[:1]
    shown, room = list(first), console.width - sum(need[c] for c in first)
    for c in columns:
        if c not in shown and need[c] <= room:
            shown.append(c)
            room -= need[c]
    shown = [c for c in columns if c in shown]
    table = Table(title=title, title_justify="left", box=None, header_style="bold", padding=(0, 1))
    for c in shown:
        justify: Literal["left", "right"] = "left" if c in ("name", "unit", "baseline") else "right"
        table.add_column(c, justify=justify, no_wrap=True, overflow="ignore")
    for i in range(len(rows)):
        table.add_row(*(cells[c][i] for c in shown))
    console.print(table)
    hidden = [c for c in columns if c not in shown]
    if hidden:
        console.print(f"  (+{len(hidden)} more in the JSON: {', '.join(hidden)})", soft_wrap=False)


@app.command()
def main(
    out: Path = typer.Option(Path("build/bench.json"), "--out", help="Where to write every row as JSON."),
    suite: list[str] = typer.Option(list(SUITES), "--suite", help=f"Suites to run: {', '.join(SUITES)}."),
    only: list[str] = typer.Option([], "--only", help="Within the pipeline suite, only these benchmarks."),
    quick: bool = typer.Option(False, "--quick", help="Shorter runs (a smoke test of the benchmarks)."),
) -> None:
    """Run the benchmarks, print a table per suite and write JSON."""
    # a summary that fits the terminal (100 columns when piped); every column is in the JSON
    console = Console(highlight=False)
    if not console.is_terminal:
        console.width = 100
    for name in suite:
        if name not in SUITES:
            raise typer.BadParameter(f"unknown suite {name!r} (valid: {', '.join(SUITES)})")
    before = _took(out)
    results: dict[str, list[dict[str, Any]]] = {}
    took: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for i, name in enumerate(suite, 1):
            last = f"; it took {before[name]:.0f} s last time" if name in before else ""
            console.print(f"suite {name} ({i} of {len(suite)}), started {time.strftime('%H:%M:%S')}{last}")
            try:
                module = importlib.import_module(SUITES[name])
            except ModuleNotFoundError as exc:
                console.print(f"suite {name}: not available ({exc})")
                continue
            kwargs: dict[str, Any] = {"quick": quick}
            if name == "pipeline":
                kwargs |= {"folder": Path(tmp), "only": only or None}
            began = time.monotonic()
            results[name] = module.run(**kwargs)
            took[name] = time.monotonic() - began
            render(console, f"{name} ({took[name]:.0f} s)", results[name])
            _write(out, results, took)  # each suite's rows as it ends: a stopped run keeps them
    console.print(f"wrote {out}")


def _write(out: Path, results: dict[str, list[dict[str, Any]]], took: dict[str, float]) -> None:
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(json.dumps({**results, "seconds": took}, indent=1, default=str) + "\n")
    tmp.replace(out)


def _took(out: Path) -> dict[str, float]:
    """Each suite's duration in the last run written to ``out`` (none when there was none)."""
    try:
        seconds = json.loads(out.read_text()).get("seconds", {})
        return {str(k): float(v) for k, v in seconds.items()}
    except (OSError, ValueError, AttributeError, TypeError):
        return {}


if __name__ == "__main__":
    app()
