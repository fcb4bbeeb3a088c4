"""``lfdfuse report --quick``: every experiment runs, the figures are images, the table compares.

The experiments (:mod:`lfdfuse.evaluate.paper`) run once for the module; the report is drawn
from their results, as ``lfdfuse report`` composes it."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path
from typing import Any

import pytest
from matplotlib.image import imread
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.evaluate.paper.compare import numbers, rows
from lfdfuse.evaluate.paper.records import PaperResults
from lfdfuse.evaluate.paper.suite import ExperimentEvent, PaperOptions, run_experiments
from lfdfuse.viz.report import ReportResult, report_json, write_report

Report = tuple[Path, list[ExperimentEvent], ReportResult]


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> Report:
    out = tmp_path_factory.mktemp("paper") / "report"
    events = list(run_experiments(PaperOptions(logs=out / "logs", seed=1, quick=True)))
    results = events[-1].results
    assert results is not None
    return out, events, write_report(results, tuple(rows(results)), out=out)


def test_progress_events_count_up_to_the_results(report: Report) -> None:
    _out, events, _result = report
    done = [e.done for e in events]
    assert done == sorted(done) and done[0] == 0 and done[-1] == events[-1].total
    assert all(e.results is None for e in events[:-1]) and isinstance(events[-1].results, PaperResults)


def test_the_results_are_frozen_records(report: Report) -> None:
    results = report[1][-1].results
    assert results is not None
    with pytest.raises(AttributeError):
        results.seed = 2  # type: ignore[misc]
    assert all(isinstance(v, tuple) for v in results.runs.values())
    assert {"keep-left", "task", "trials", "pass-left"} <= set(results.learned)


def test_index_html_has_the_comparison_and_every_figure(report: Report) -> None:
    out, _events, result = report
    html = (out / "index.html").read_text()
    assert html.count("<tr>") == len(result.comparison) + 1
    assert len(result.comparison) >= 10
    assert len(result.figures) >= 8
    for fig in result.figures:
        assert f'src="{fig.file}"' in html
        img = imread(out / fig.file)
        assert img.shape[1] >= 800 and img.shape[0] >= 500, fig.file
        assert img[:, :, :3].std() > 0.05, fig.file  # not a blank canvas


def test_report_json_has_every_number(report: Report) -> None:
    out, _events, _result = report
    data = json.loads((out / "report.json").read_text())
    assert data["format"] == "lfdfuse/paper-report@1" and data["quick"] is True
    rows = data["comparison"]
    assert all(r["paper"] and r["ours"] and r["source"] for r in rows)
    assert {r["agrees"] for r in rows} <= {True, False, None}
    task = data["runs"]["task"]
    assert len(task) == 2 and all("left_range_mean_m" in r for r in task)
    assert len(data["weights"]["steps"]) >= 3
    for f in data["figures"]:
        assert (out / f["file"]).is_file()
    assert (out / "logs" / "three-goals.seg.mcap").is_file()


def test_report_into_a_file_is_a_user_error(tmp_path: Path) -> None:
    target = tmp_path / "file"
    target.write_text("x")
    res = CliRunner().invoke(app, ["report", "-o", str(target), "--quick"])
    assert res.exit_code == 1 and res.output.startswith("error:")


def test_the_report_on_two_workers_is_byte_identical(
    report: Report, tmp_path: Path, dask_cluster: Any
) -> None:
    """The same grid on a 2-worker Dask LocalCluster (the cells in any order): the same report.json.

    Its numbers are those of the grid's results; the figures are drawn from them alone (the
    report's figures are not drawn again here: the same list of files and captions)."""
    out, _events, result = report
    other = tmp_path / "report"
    events = list(
        run_experiments(PaperOptions(logs=other / "logs", seed=1, quick=True), executor=dask_cluster)
    )
    results = events[-1].results
    assert results is not None
    figs = [{"file": f.file, "caption": f.caption} for f in result.figures]
    text = report_json(numbers(results, tuple(rows(results)), figures=figs))
    assert text.encode() == (out / "report.json").read_bytes()


def test_the_report_json_shows_the_spread_of_every_rate(report: Report) -> None:
    out, _events, _result = report
    data = json.loads((out / "report.json").read_text())
    for name, s in data["spread"].items():
        assert s["runs"] == len(data["runs"][name]) and 0 <= s["successes"] <= s["runs"], name
        lo, hi = s["ci95"]
        assert 0.0 <= lo <= s["rate"] <= hi <= 1.0, name


def test_a_quick_report_judges_nothing_and_a_full_one_follows_its_numbers(report: Report) -> None:
    """A smoke run (one run per controller) agrees with nothing and differs from nothing; judged
    in full, a style row's verdict follows from the offset it prints beside it."""
    results = report[1][-1].results
    assert results is not None
    assert all(r.agrees is None for r in rows(results))
    judged = {r.experiment: r for r in rows(dataclasses.replace(results, quick=False))}
    assert any(r.agrees is not None for r in judged.values())
    for style, want in (("keep-left", "left"), ("keep-center", "centre"), ("keep-right", "right")):
        row = judged[f"{style} learned and run in the small world"]
        m = re.search(r"keeps (\w+) \(median ([0-9.]+) m (left|right) of centre", row.ours)
        assert m is not None, row.ours
        shown = "centre" if float(m.group(2)) <= 0.25 else m.group(3)
        assert m.group(1) == shown and row.agrees == (shown == want), row
