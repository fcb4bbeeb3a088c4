"""Reading a segmented log back: what segment wrote, and one clear error for a broken message."""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import orjson
import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.errors import LogError
from lfdfuse.log import LogWriter
from lfdfuse.log.reader import iter_raw, read_run
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented, read_segmented_and_run
from tests.segment.test_segment import write_log

runner = CliRunner()


@pytest.fixture(scope="module")
def segmented(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    d = tmp_path_factory.mktemp("read")
    write_log(d / "d.mcap", n=60, wall_steps=set(range(10, 30)), goal_steps={25: "red", 50: "green"})
    res = segment_file(
        d / "d.mcap", out=d / "s.mcap", behaviors="avoid,attract,wander_left,wall_attract_left"
    )
    return d / "s.mcap", res


def test_read_returns_what_segment_wrote(segmented: tuple[Path, Any]) -> None:
    path, res = segmented
    run = read_segmented(path)
    assert run.names == res.names and np.array_equal(run.t_ns, res.t_ns)
    n, k = len(res.t_ns), len(res.names)
    assert run.vectors.shape == (n, k, 2) and run.applicable.shape == run.goal_met.shape == (n, k)
    assert (np.hypot(run.vectors[..., 0], run.vectors[..., 1]) <= 1 + 1e-6).all()
    assert np.array_equal(run.bac, (run.applicable * (1 << np.arange(k))).sum(axis=1))
    assert np.array_equal(run.bac, res.segmentation.bac) and np.array_equal(run.informative, res.informative)
    assert run.segments == res.segmentation.segments
    assert np.array_equal(run.segment_of, res.segmentation.segment_of)
    assert (np.diff(run.t_ns) == 100_000_000).all()


def _rewrite(
    src: Path, out: Path, topic: str, change: Callable[[int, dict[str, Any]], dict[str, Any]]
) -> None:
    """A copy of ``src`` with every ``topic`` message's JSON passed through ``change``."""
    seen = -1
    with LogWriter(out, metadata={}) as log:
        for raw in iter_raw(src):
            if raw.topic == topic:
                seen += 1
                raw = replace(raw, data=orjson.dumps(change(seen, orjson.loads(raw.data))))
            log.copy(raw)


def _behavior(field: str, value: object) -> Callable[[int, dict[str, Any]], dict[str, Any]]:
    def change(i: int, m: dict[str, Any]) -> dict[str, Any]:
        if i == 5:
            m["behaviors"][1][field] = value
        return m

    return change


BROKEN: dict[str, tuple[str, Callable[[int, dict[str, Any]], dict[str, Any]], str]] = {
    # a number written as a string was read as a number before (float("0.5")): exit 0
    "x-as-string": ("/lfd/behaviors", _behavior("x", "0.5"), "x of 'attract_red' is not a number"),
    "applicable-as-int": ("/lfd/behaviors", _behavior("applicable", 1), "is not true or false"),
    "extra-field": ("/lfd/behaviors", _behavior("weight", 1.0), "unknown field: 'weight'"),
    "informative-missing": (
        "/lfd/demo",
        lambda i, m: {k: v for k, v in m.items() if k != "informative"},
        "missing: 'informative'",
    ),
    "bac-float": (
        "/lfd/bac",
        lambda i, m: {**m, "bac": float(m["bac"])},
        "bac is not a non-negative integer",
    ),
    "bac-beyond-64-bits": ("/lfd/bac", lambda i, m: {**m, "bac": 2**64 - 1}, "bits beyond"),
    "stamp-negative": ("/lfd/segment", lambda i, m: {**m, "timestamp": {"sec": -1, "nsec": 0}}, "timestamp"),
    "goal-number": ("/lfd/segment", lambda i, m: {**m, "goal": 3}, "goal (string or null) is not a string"),
}


@pytest.mark.parametrize("case", list(BROKEN))
def test_a_broken_message_is_one_error_line_naming_file_and_channel(
    case: str, segmented: tuple[Path, Any], tmp_path: Path
) -> None:
    topic, change, reason = BROKEN[case]
    _rewrite(segmented[0], tmp_path / "b.mcap", topic, change)
    with pytest.raises(LogError, match=re.escape(reason)):
        read_segmented(tmp_path / "b.mcap")
    old = os.getcwd()
    os.chdir(tmp_path)
    try:
        res = runner.invoke(app, ["estimate", "b.mcap", "-o", "t.yaml"])
    finally:
        os.chdir(old)
    assert res.exit_code == 1, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: b.mcap: a " + topic + " message at t="), lines
    assert reason in lines[0] and not (tmp_path / "t.yaml").exists()


def test_an_untouched_copy_reads_the_same(segmented: tuple[Path, Any], tmp_path: Path) -> None:
    _rewrite(segmented[0], tmp_path / "same.mcap", "/lfd/behaviors", lambda i, m: m)
    a, b = read_segmented(segmented[0]), read_segmented(tmp_path / "same.mcap")
    assert np.array_equal(a.vectors, b.vectors) and np.array_equal(a.bac, b.bac) and a.segments == b.segments


# --- read_segmented_and_run: both reads from one pass, with their errors in their order ---------


def _error(read: Callable[[Path], object], path: Path) -> str:
    with pytest.raises(LogError) as info:
        read(path)
    return str(info.value)


def _both(path: Path) -> str:
    read_segmented(path)  # the segmented read first, as learn read them before
    return _error(read_run, path)


def _scan_without_ranges(i: int, m: dict[str, Any]) -> dict[str, Any]:
    return {"nope": 1} if i == 3 else m


def test_one_pass_reads_what_the_two_reads_read(segmented: tuple[Path, Any]) -> None:
    path = segmented[0]
    seg, run = read_segmented_and_run(path)
    alone, raw = read_segmented(path), read_run(path)
    for name in alone.__dataclass_fields__:
        a, b = getattr(alone, name), getattr(seg, name)
        assert np.array_equal(a, b) if isinstance(a, np.ndarray) else a == b, name
    for name in raw.__dataclass_fields__:
        a, b = getattr(raw, name), getattr(run, name)
        if isinstance(a, np.ndarray) or a is None:
            assert (a is None and b is None) or (a.dtype == b.dtype and np.array_equal(a, b)), name
        else:
            assert a == b, name


@pytest.mark.parametrize("case", list(BROKEN))
def test_one_pass_reports_a_broken_segmented_message_first(
    case: str, segmented: tuple[Path, Any], tmp_path: Path
) -> None:
    """Broken in both: the segmented read's error, though the broken scan comes earlier."""
    topic, change, _reason = BROKEN[case]
    _rewrite(segmented[0], tmp_path / "b.mcap", topic, change)
    assert _error(read_segmented_and_run, tmp_path / "b.mcap") == _error(read_segmented, tmp_path / "b.mcap")
    _rewrite(tmp_path / "b.mcap", tmp_path / "bb.mcap", "/scan", _scan_without_ranges)
    assert _error(read_segmented_and_run, tmp_path / "bb.mcap") == _error(
        read_segmented, tmp_path / "bb.mcap"
    )


def test_one_pass_reports_a_broken_run_as_read_run_does(segmented: tuple[Path, Any], tmp_path: Path) -> None:
    _rewrite(segmented[0], tmp_path / "s.mcap", "/scan", _scan_without_ranges)
    got = _error(read_segmented_and_run, tmp_path / "s.mcap")
    assert got == _both(tmp_path / "s.mcap") and "a /scan message at t=" in got
    with LogWriter(tmp_path / "n.mcap", metadata={}) as log:  # no commands: read_run's last check
        for raw in iter_raw(segmented[0]):
            if raw.topic != "/cmd_vel":
                log.copy(raw)
    got = _error(read_segmented_and_run, tmp_path / "n.mcap")
    assert got == _both(tmp_path / "n.mcap") and "no /cmd_vel messages" in got
