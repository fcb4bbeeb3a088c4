"""``index.html`` of the report: the comparison table first, then the figures with captions."""

from __future__ import annotations

from collections.abc import Sequence
from html import escape
from pathlib import Path
from typing import Any, Protocol

from lfdfuse import __version__
from lfdfuse.evaluate.paper.compare import Row
from lfdfuse.files import write_text_atomic

_CSS = """
body { font-family: system-ui, sans-serif; max-width: 1100px; margin: 2em auto; padding: 0 1em; color: #222; }
table { border-collapse: collapse; width: 100%; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 0.35em 0.5em; vertical-align: top; text-align: left; }
th { background: #f3f3f3; }
td.yes { color: #1a7f37; font-weight: bold; } td.no { color: #cf222e; font-weight: bold; } td.na { color: #777; }
figure { margin: 2em 0; } figure img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: 0.92em; color: #444; } .note { color: #555; font-size: 0.88em; }
"""


class _Fig(Protocol):
    @property
    def file(self) -> str: ...

    @property
    def caption(self) -> str: ...


def _verdict(a: bool | None) -> tuple[str, str]:
    if a is None:
        return "na", "not comparable"
    return ("yes", "agrees") if a else ("no", "DIFFERS")


def page(*, figures: Sequence[_Fig], rows: Sequence[Row], numbers: dict[str, Any]) -> str:
    differ = [r for r in rows if r.agrees is False]
    head = (
        f"<p>Every number on the right was measured by this run (seed {numbers['seed']}"
        f"{', quick mode: shorter runs, fewer starts and trials' if numbers['quick'] else ''}); "
        "the paper's side is quoted from its text. All of it is in <code>report.json</code>; the "
        "demonstrations, tables and runs are in <code>logs/</code> (open any <code>.mcap</code> in Foxglove or Lichtblick).</p>"
    )
    if differ:
        head += (
            "<p><b>Where we differ from the paper:</b> "
            + "; ".join(escape(r.experiment) for r in differ)
            + ".</p>"
        )
    else:
        head += "<p>No checked claim differs from the paper in this run.</p>"
    trs = []
    for r in rows:
        cls, word = _verdict(r.agrees)
        note = f'<div class="note">{escape(r.note)}</div>' if r.note else ""
        trs.append(
            f"<tr><td>{escape(r.experiment)}<div class='note'>{escape(r.source)}</div></td>"
            f"<td>{escape(r.paper)}</td><td>{escape(r.ours)}{note}</td><td class='{cls}'>{word}</td></tr>"
        )
    figs = "\n".join(
        f'<figure><img src="{escape(f.file)}" alt="{escape(f.caption)}"><figcaption>{escape(f.caption)} '
        f"<code>{escape(f.file)}</code></figcaption></figure>"
        for f in figures
    )
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>lfdfuse: the paper's experiments, rerun</title>
<style>{_CSS}</style></head><body>
<h1>Learning Behavior Fusion from Demonstration — the experiments, rerun with lfdfuse {escape(__version__)}</h1>
{head}
<h2>The paper beside us</h2>
<table><tr><th>experiment</th><th>paper</th><th>lfdfuse, measured now</th><th></th></tr>
{"".join(trs)}
</table>
<h2>Figures</h2>
{figs}
</body></html>
"""


def write_index(path: Path, *, figures: Sequence[_Fig], rows: Sequence[Row], numbers: dict[str, Any]) -> None:
    write_text_atomic(path, page(figures=figures, rows=rows, numbers=numbers))


def markdown_table(rows: Sequence[Row]) -> str:
    """The comparison as a Markdown table (for notes and the README)."""
    lines = ["| experiment | paper | lfdfuse (measured) | |", "|---|---|---|---|"]
    for r in rows:
        word = _verdict(r.agrees)[1]
        lines.append(f"| {r.experiment} ({r.source}) | {r.paper} | {r.ours} | {word} |")
    return "\n".join(lines)
