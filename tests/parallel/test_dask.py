"""Serial and a 2-worker Dask LocalCluster give byte-identical JSON (evaluate, execute --starts);
many logs give one row each and a summary; a log that fails carries its own line, the rest carry on."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.errors import LfdError
from lfdfuse.evaluate.batch import BASELINES, evaluate_logs
from lfdfuse.execute.starts import StartsOptions, run_starts
from lfdfuse.parallel import Batch, Executor, InProcess
from lfdfuse.segment.pipeline import segment_file
from tests.parallel.conftest import CORRIDOR_TABLE

pytest.importorskip("distributed")

#: what these tests compare (serial against the cluster, a batch against one log) holds for any
#: number of folds; two fit each method twice per log instead of five times (5-fold is
#: tests/evaluate's)
FOLDS = 2


@pytest.fixture()
def cluster(dask_cluster: Executor) -> Executor:
    return dask_cluster


def test_execute_starts_serial_and_on_two_workers_are_byte_identical(cluster: Executor) -> None:
    opts = StartsOptions(table=CORRIDOR_TABLE, world="corridor", starts=4, max_time_s=3.0, seed=11)
    serial = run_starts(opts, executor=InProcess()).result().to_dict()
    dask = run_starts(opts, executor=cluster).result().to_dict()
    assert json.dumps(serial, indent=1) == json.dumps(dask, indent=1)
    assert len(serial["starts"]) == 4


def test_evaluate_many_logs_serial_and_on_two_workers_are_byte_identical(
    cluster: Executor, short_demos: list[Path], tmp_path: Path
) -> None:
    missing = tmp_path / "gone.mcap"
    paths = [*short_demos, missing]
    serial = evaluate_logs(paths, executor=InProcess(), seed=2, folds=FOLDS)
    events = list(serial)
    assert events[-1].failed == 1 and events[-1].done == 2
    dask = evaluate_logs(paths, executor=cluster, seed=2, folds=FOLDS)
    a, b = serial.result().to_dict(), dask.result().to_dict()
    assert json.dumps(a, indent=1) == json.dumps(b, indent=1)
    logs = a["logs"]
    assert [e["path"] for e in logs] == [str(p) for p in paths]
    assert logs[0]["prepared"] == ["segment"] and "gone.mcap" in logs[2]["error"]
    assert a["summary"]["logs"] == 2 and a["summary"]["failed"] == 1
    for b_name in BASELINES:
        beats = a["summary"]["fused_beats"][b_name]
        won = sum(
            e["methods"]["fused"]["heading_error_deg"] < e["methods"][b_name]["heading_error_deg"]
            for e in logs[:2]
        )
        assert beats["logs"] == won and beats["of"] == 2


def test_a_segmented_log_in_a_batch_scores_as_it_does_alone(short_demos: list[Path], tmp_path: Path) -> None:
    seg = segment_file(short_demos[0], out=tmp_path / "a.seg.mcap", lag_s=None)  # as `lfdfuse segment`
    logs = [Path(seg.out), short_demos[0]]
    batch = evaluate_logs(logs, executor=InProcess(), folds=FOLDS).result().to_dict()
    before, on_the_way = (
        {k: v for k, v in e.items() if k not in ("path", "prepared")} for e in batch["logs"]
    )
    assert before == on_the_way  # segmented before or on the way: the same numbers
    assert [e["prepared"] for e in batch["logs"]] == [[], ["segment"]]


def test_cli_evaluate_many_on_a_cluster_prints_rows_summary_and_fails_for_a_bad_log(
    cluster: Executor, short_demos: list[Path], tmp_path: Path
) -> None:
    """The real command on the cluster (by --scheduler, the module's 2 workers) and in-process."""
    address = cluster.address  # type: ignore[attr-defined]
    out_w, out_s = tmp_path / "w.json", tmp_path / "s.json"
    bad = tmp_path / "not-a-log.mcap"
    bad.write_text("hello")
    args = ["evaluate", *map(str, short_demos), str(bad), "--folds", str(FOLDS)]
    res = CliRunner(env={"COLUMNS": "200"}).invoke(app, [*args, "--scheduler", address, "--json", str(out_w)])
    assert res.exit_code == 1, res.output
    assert "error: " in res.output and "not-a-log.mcap" in res.output
    assert "fused better" in res.output and re.search(r"(?m)^ +straight +\d+/2", res.output), res.output
    for p in short_demos:
        assert p.name in res.output
    res = CliRunner().invoke(app, [*args, "--json", str(out_s)])
    assert res.exit_code == 1
    assert out_w.read_bytes() == out_s.read_bytes()
    entry = json.loads(out_s.read_text())["logs"][0]
    one = tmp_path / "one.json"
    res = CliRunner().invoke(
        app, ["evaluate", str(short_demos[0]), "--folds", str(FOLDS), "--json", str(one)]
    )
    assert res.exit_code == 0, res.output
    single = json.loads(one.read_text())  # one log: today's object, the same numbers as in a batch
    assert single == {k: v for k, v in entry.items() if k not in ("path", "prepared")}


def test_cli_workers_starts_a_local_cluster(tmp_path: Path) -> None:
    rep = tmp_path / "rate.json"
    args = ["execute", str(CORRIDOR_TABLE), "--world", "corridor", "--starts", "2", "--max-time", "2"]
    res = CliRunner().invoke(app, [*args, "--workers", "1", "--report", str(rep)])
    assert res.exit_code == 0, res.output
    serial = tmp_path / "serial.json"
    assert CliRunner().invoke(app, [*args, "--report", str(serial)]).exit_code == 0
    assert rep.read_bytes() == serial.read_bytes()


def _square_unless_three(x: int) -> int:
    if x == 3:
        raise LfdError("three is bad")
    return x * x


def test_jobs_that_wait_give_the_same_outcomes_on_two_workers(cluster: Executor) -> None:
    """Jobs handed out as the jobs they wait for finish (2 in flight), a failure stopping what waits."""
    items = list(range(8))
    after = [(), (), (0,), (), (3,), (2, 4), (), (5,)]
    costs = [1.0, 5.0, 2.0, 1.0, 1.0, 1.0, 3.0, 1.0]

    def outcomes(ex: Executor) -> list[tuple[int | None, str | None]]:
        batch = Batch(_square_unless_three, items, executor=ex, reduce=list, after=after, costs=costs)
        events = list(batch)
        assert events[-1].failed == 4 and events[-1].done == 4  # 3, and 4, 5, 7 waiting on it
        return [(o.value, o.error) for o in batch.outcomes]

    serial = outcomes(InProcess())
    assert serial == outcomes(cluster)
    assert [e for _, e in serial].count("not run: a job it waits for failed") == 3
