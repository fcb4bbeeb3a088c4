"""Writing the paper report from the experiments' results: the figures, ``index.html``, ``report.json``.

:func:`write_report` draws what it is handed — the :class:`PaperResults` of
:func:`lfdfuse.evaluate.paper.suite.run_experiments` and the comparison rows of
:func:`lfdfuse.evaluate.paper.compare.rows` — into ``DIR``: one PNG per figure, ``index.html``
with the comparison table first, and ``report.json`` with every number. It runs no stage.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lfdfuse.errors import LfdError
from lfdfuse.evaluate.paper.compare import Row, numbers
from lfdfuse.evaluate.paper.records import PaperResults
from lfdfuse.files import write_text_atomic
from lfdfuse.viz.html import write_index
from lfdfuse.viz.plot import save_figure
from lfdfuse.viz.report_figures import report_figures


@dataclass(frozen=True)
class ReportFigure:
    file: str
    caption: str


@dataclass(frozen=True)
class ReportResult:
    out: str
    figures: tuple[ReportFigure, ...]
    comparison: tuple[Row, ...]
    numbers: dict[str, Any]


def write_report(results: PaperResults, rows: Sequence[Row], *, out: Path) -> ReportResult:
    """Draw every figure of ``results`` into ``out``, then ``report.json`` and ``index.html``."""
    if out.exists() and not out.is_dir():
        raise LfdError(f"cannot write the report to {out}: it is a file")
    out.mkdir(parents=True, exist_ok=True)
    figs = []
    for fig, name, caption in report_figures(results):
        save_figure(fig, out / name)
        figs.append(ReportFigure(name, caption))
    data = numbers(results, rows, figures=[{"file": f.file, "caption": f.caption} for f in figs])
    write_text_atomic(out / "report.json", report_json(data))
    write_index(out / "index.html", figures=figs, rows=rows, numbers=data)
    return ReportResult(str(out), tuple(figs), tuple(rows), data)


def report_json(data: dict[str, Any]) -> str:
    """``report.json``'s text: every number of the report (:func:`numbers`), as written."""
    return json.dumps(data, indent=1, allow_nan=False) + "\n"
