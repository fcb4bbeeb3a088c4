"""`make bench` prints a summary per suite that fits the terminal; every column stays in the JSON."""

from __future__ import annotations

from rich.console import Console

from tests.bench.run import render


def test_a_wide_suite_is_summarised_whole_at_80_columns() -> None:
    rows = [
        {
            "name": f"wander_right_and_left_{i}",
            "ms": 12.5 * i,
            "ratio": 1.07,
            **{f"extra_{k}": 123456.0 for k in range(8)},
        }
        for i in range(3)
    ]
    console = Console(width=80, record=True, highlight=False)
    render(console, "suite", rows)
    text = console.export_text()
    lines = text.splitlines()
    assert all(len(ln) <= 80 for ln in lines)
    assert "…" not in text  # no cell cut
    for row in rows:
        assert any(ln.strip().startswith(row["name"]) for ln in lines), text  # every name whole
    assert "ms" in lines[1] and "ratio" in lines[1], text
    hidden = [ln for ln in lines if "more in the JSON" in ln]
    assert len(hidden) == 1 and "extra_7" in hidden[0], text


def test_a_narrow_suite_shows_every_column() -> None:
    console = Console(width=80, record=True, highlight=False)
    render(console, "s", [{"name": "a", "x": 1.0}, {"name": "b", "y": 2}])
    text = console.export_text()
    assert "more in the JSON" not in text and " x " in f" {text} " and "y" in text
