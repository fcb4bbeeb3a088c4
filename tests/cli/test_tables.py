"""Tables fit the terminal without a cut cell: wide ones are shown in column groups."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rich.console import Console
from rich.table import Table
from typer.testing import CliRunner

from lfdfuse.cli import common
from lfdfuse.cli.main import app
from lfdfuse.cli.tables import fitted
from lfdfuse.network.table import FusionTable, dump_table

NUMBER = re.compile(r"[-+]?\d[\d.,/±%°]*\*?")


def _render(table: Table, width: int) -> str:
    out = Console(width=width, record=True, highlight=False, color_system=None, file=open("/dev/null", "w"))
    for part in fitted(table, width):
        out.print(part)
    return out.export_text()


@given(
    st.integers(min_value=40, max_value=120),
    st.lists(st.text("abcdef ", min_size=1, max_size=14), min_size=3, max_size=14),
    st.lists(st.lists(st.floats(-999.0, 99_999.0, allow_nan=False), min_size=14, max_size=14), max_size=5),
)
def test_every_cell_is_shown_whole(width: int, headers: list[str], rows: list[list[float]]) -> None:
    table = Table(box=None, header_style="bold")
    table.add_column("row", no_wrap=True)
    for h in headers:
        table.add_column(h, justify="right")
    cells = [[f"r{i}", *(f"{v:.1f}" for v in row[: len(headers)])] for i, row in enumerate(rows)]
    for c in cells:
        table.add_row(*c)
    text = _render(table, width)
    assert "…" not in text
    assert all(len(line) <= width for line in text.splitlines())
    shown = NUMBER.findall(text)
    for c in cells:
        for v in c[1:]:
            assert v in shown, f"{v} cut at {width} columns"


@pytest.fixture
def terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    """The CLI's console as an 80-column terminal without colour."""
    monkeypatch.setattr(common.console, "_force_terminal", True)
    monkeypatch.setattr(common.console, "_color_system", None)
    monkeypatch.setattr(common.console, "_width", 80)
    monkeypatch.setattr(common.console, "soft_wrap", False)  # a terminal wraps prose at its width


def test_the_full_preset_table_keeps_every_number_at_80_columns(
    tmp_path: Path, sample_dir: Path, terminal: None
) -> None:
    runner = CliRunner()
    seg = tmp_path / "full.seg.mcap"
    res = runner.invoke(
        app, ["segment", str(sample_dir / "keep-left-building.mcap"), "--behaviors", "full", "-o", str(seg)]
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["estimate", str(seg), "--method", "nnls", "-o", str(tmp_path / "t.yaml")])
    assert res.exit_code == 0, res.output
    narrow = res.stdout
    assert "…" not in narrow and all(len(ln) <= 80 for ln in narrow.splitlines())
    common.console._force_terminal = False  # piped: the table whole, at its own width
    common.console.soft_wrap = True
    whole = runner.invoke(app, ["inspect", str(tmp_path / "t.yaml")]).stdout
    rows = [ln for ln in whole.splitlines() if re.match(r"\s*\d+\??\s", ln)]
    assert rows, whole
    for ln in rows:  # every number of every BAC row is in the narrow rendering
        for n in NUMBER.findall(ln):
            assert n in narrow, f"{n} of '{ln.strip()}' missing at 80 columns"


def test_the_readme_commands_tables_fit_80_columns(
    tmp_path: Path, three_goal_segmented: Path, three_goal_table: FusionTable, terminal: None
) -> None:
    """What the README's table commands print on an 80-column terminal: no line wider, no number
    cut (``…``), every number of the table's rows shown (the learned table, the segmented demo,
    the held-out evaluation, a success rate over starts, the worlds, a real robot bag)."""
    from tests.conftest import SHARED

    table = tmp_path / "task.yaml"
    table.write_text(dump_table(three_goal_table))
    demo = str(three_goal_segmented)
    commands = [
        ["inspect", str(table)],
        ["inspect", demo],
        ["evaluate", demo, "--holdout", "0.3"],
        ["execute", str(table), "--starts", "3", "--max-time", "5"],
        ["worlds"],
    ]
    bag = SHARED / "realdata" / "ros1" / "neato-keyboard-middle.bag"
    if bag.exists():
        commands.append(["inspect", str(bag)])
    runner = CliRunner()
    for args in commands:
        res = runner.invoke(app, args)
        assert res.exit_code == 0, (args, res.output)
        wide = [ln for ln in res.stdout.splitlines() if len(ln) > 80]
        cut = re.findall(r"\S*(?:\d…|…\d)\S*", res.stdout)  # metadata prose may shorten a name
        assert not wide and not cut, (args, wide or cut)
    # the table's rows, piped whole, against what the terminal showed
    common.console._force_terminal = False
    common.console.soft_wrap = True
    whole = runner.invoke(app, ["inspect", str(table)]).stdout
    common.console._force_terminal = True
    common.console.soft_wrap = False
    narrow = runner.invoke(app, ["inspect", str(table)]).stdout
    rows = [ln for ln in whole.splitlines() if re.match(r"\s*\d+\??\s", ln)]
    assert rows, whole
    for ln in rows:
        for n in NUMBER.findall(ln):
            assert n in narrow, f"{n} of '{ln.strip()}' missing at 80 columns"
