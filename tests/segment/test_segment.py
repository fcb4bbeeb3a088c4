"""Segmentation: boundaries on known goal times and precondition flips; the real CLI."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from lfdfuse.behaviors.primitives import BehaviorOutputs
from lfdfuse.cli.main import app
from lfdfuse.log import LogWriter
from lfdfuse.log import messages as msg
from lfdfuse.log.reader import iter_messages
from lfdfuse.robot.readings import Detection, ScanGeometry
from lfdfuse.segment.goals import segment_goals, segment_outputs
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from tests.conftest import mcap_check

GEOM = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 8.0)
runner = CliRunner()


def write_log(
    path: Path,
    *,
    n: int,
    wall_steps: set[int],
    goal_steps: dict[int, str],
    cmd: bool = True,
    scan: bool = True,
) -> None:
    """A synthetic demo: a left wall at 1 m on ``wall_steps``; a target within reach on ``goal_steps``."""
    with LogWriter(path, metadata={"seed": "0"}) as log:
        for k in range(n):
            t = k * 100_000_000
            r = np.full(181, 8.0)
            if k in wall_steps:
                r[135:] = 1.0
            if scan:
                log.write("/scan", t, msg.laser_scan(t, r, GEOM))
            dets = []
            for name in ("red", "green"):
                near = goal_steps.get(k) == name
                dets.append(Detection(name, 0.1, 0.5 if near else 3.0))
            log.write("/targets", t, msg.target_detections(t, dets))
            if cmd:
                log.write("/cmd_vel", t, msg.twist(t, 0.3 if k % 7 else 0.0, 0.1 if k % 7 else 0.0))


def test_goal_boundaries_land_exactly_on_goal_times(tmp_path: Path) -> None:
    goals = {30: "red", 31: "red", 80: "green", 140: "red"}  # red met twice: two segments
    write_log(tmp_path / "d.mcap", n=200, wall_steps=set(), goal_steps=goals)
    res = segment_file(tmp_path / "d.mcap", out=tmp_path / "s.mcap", behaviors="avoid,attract,wander")
    segs = res.segmentation.segments
    assert [(s.start, s.stop, s.goal) for s in segs] == [
        (0, 31, "attract_red"),
        (31, 81, "attract_green"),
        (81, 141, "attract_red"),
        (141, 200, None),
    ]


def test_bac_boundaries_land_exactly_on_precondition_flips(tmp_path: Path) -> None:
    wall = set(range(20, 50)) | set(range(90, 95))
    write_log(tmp_path / "d.mcap", n=120, wall_steps=wall, goal_steps={})
    res = segment_file(
        tmp_path / "d.mcap",
        out=tmp_path / "s.mcap",
        behaviors="avoid,wander_left,wander_right,wall_attract_left",
    )
    runs = res.segmentation.bac_runs(res.segmentation.segments[0])
    assert [(s, e) for _, s, e in runs] == [(0, 20), (20, 50), (50, 90), (90, 95), (95, 120)]
    # bits: avoid=1, wander_left=2, wander_right=4, wall_attract_left=8
    assert [b for b, _, _ in runs] == [6, 15, 6, 15, 6]
    # standing still every 7th step: no heading information there
    assert res.informative.tolist() == [k % 7 != 0 for k in range(120)]


def test_flickering_goal_is_one_achievement() -> None:
    met = np.zeros((50, 1), dtype=bool)
    met[[10, 12, 13, 40]] = True
    assert segment_goals(met, ("attract_red",), refractory_steps=10) == [
        (10, "attract_red"),
        (40, "attract_red"),
    ]


def test_segment_outputs_partition_every_step() -> None:
    rng = np.random.default_rng(0)
    n, k = 300, 4
    app = rng.random((n, k)) < 0.5
    goal = np.zeros((n, k), dtype=bool)
    goal[rng.integers(0, n, 6), rng.integers(0, k, 6)] = True
    out = segment_outputs(BehaviorOutputs(("a", "b", "c", "d"), np.zeros((n, k, 2)), app, goal))
    covered = np.concatenate([np.arange(s.start, s.stop) for s in out.segments])
    assert covered.tolist() == list(range(n))
    for s in out.segments:
        runs = out.bac_runs(s)
        assert sum(e - b for _, b, e in runs) == s.stop - s.start
        for b, st, en in runs:
            assert (out.bac[st:en] == b).all()


def test_segmenting_is_deterministic_and_idempotent(
    tmp_path: Path, sample_dir: Path, keep_left_segmented: Path
) -> None:
    src = sample_dir / "keep-left-building.mcap"
    told: list[float] = []
    segment_file(src, out=tmp_path / "a.mcap", progress=lambda done, total: told.append(done / total))
    # the progress bar moves through reading and writing, never back, and ends full
    assert told == sorted(told) and told[-1] == 1.0
    assert len({round(f, 2) for f in told if 0.0 < f < 0.25}) >= 3  # while reading
    assert len({round(f, 2) for f in told if 0.34 < f < 1.0}) >= 3  # while writing
    # the session's segmentation of src (default options, another run): the same bytes
    assert (tmp_path / "a.mcap").read_bytes() == keep_left_segmented.read_bytes()
    segment_file(tmp_path / "a.mcap", out=tmp_path / "c.mcap")  # a segmented file again
    topics = [t for t, *_ in iter_messages(tmp_path / "c.mcap")]
    assert topics.count("/lfd/bac") == topics.count("/scan")  # replaced, not duplicated
    a, c = read_segmented(tmp_path / "a.mcap"), read_segmented(tmp_path / "c.mcap")
    assert np.array_equal(a.vectors, c.vectors) and np.array_equal(a.bac, c.bac) and a.segments == c.segments


def test_three_goal_sample_has_three_goal_segments_in_order(three_goal_segmented: Path) -> None:
    # the sample segmented with the defaults (the session's), its segments read back from the file
    goals = [s.goal for s in read_segmented(three_goal_segmented).segments]
    assert goals[:3] == ["attract_red", "attract_green", "attract_blue"]
    assert all(g is None for g in goals[3:]) and len(goals) <= 4
    report = mcap_check(three_goal_segmented)
    assert '"ok": true' in report


def _cli_error(args: list[str], cwd: Path) -> str:
    before = sorted(os.listdir(cwd))
    res = runner.invoke(app, args)
    assert res.exit_code == 1, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert sorted(os.listdir(cwd)) == before
    return lines[0]


def test_segment_bad_input(tmp_path: Path, sample_dir: Path) -> None:
    old = os.getcwd()
    os.chdir(tmp_path)
    try:
        write_log(tmp_path / "nocmd.mcap", n=10, wall_steps=set(), goal_steps={}, cmd=False)
        assert "no /cmd_vel" in _cli_error(["segment", "nocmd.mcap"], tmp_path)
        write_log(tmp_path / "noscan.mcap", n=10, wall_steps=set(), goal_steps={}, scan=False)
        assert "no /scan" in _cli_error(["segment", "noscan.mcap"], tmp_path)
        with LogWriter(tmp_path / "empty.mcap", metadata={}):
            pass
        assert "no /scan and no /cmd_vel" in _cli_error(["segment", "empty.mcap"], tmp_path)
        data = (sample_dir / "keep-left-building.mcap").read_bytes()
        (tmp_path / "cut.mcap").write_bytes(data[: len(data) // 2])
        assert "truncated MCAP file" in _cli_error(["segment", "cut.mcap"], tmp_path)
        assert "unknown behaviour 'fly'" in _cli_error(
            ["segment", str(sample_dir / "keep-left-building.mcap"), "-b", "avoid,fly", "-o", "x.mcap"],
            tmp_path,
        )
    finally:
        os.chdir(old)


def test_segment_cli_prints_segments(tmp_path: Path, sample_dir: Path) -> None:
    out = tmp_path / "s.mcap"
    res = runner.invoke(app, ["segment", str(sample_dir / "three-goals-building.mcap"), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "segment 0 → attract_red" in res.output and "segment 2 → attract_blue" in res.output
    assert "BAC (samples)" in res.output
    res = runner.invoke(app, ["inspect", str(out)])
    assert "segment 1 → attract_green" in res.output


def test_default_output_name(tmp_path: Path, sample_dir: Path) -> None:
    src = tmp_path / "demo.mcap"
    src.write_bytes((sample_dir / "pass-left-obstacles.mcap").read_bytes())
    before = src.read_bytes()
    res = runner.invoke(app, ["segment", str(src)])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "demo.seg.mcap").exists()
    assert src.read_bytes() == before  # the input is never touched


def test_messy_scans_are_read_and_segmented(tmp_path: Path) -> None:
    """null (NaN/inf in JSON), zero and max-range sentinels, commands out of time order."""
    import orjson

    with LogWriter(tmp_path / "m.mcap", metadata={}) as log:
        for k in range(40):
            t = k * 100_000_000
            scan = msg.laser_scan(t, np.full(181, 8.0), GEOM)
            scan["ranges"] = [None if i % 3 == 0 else (0.0 if i % 3 == 1 else 1.5) for i in range(181)]
            log.write_raw("/scan", t, orjson.dumps(scan))
        for k in reversed(range(40)):  # commands written newest first
            t = k * 100_000_000 + 50_000_000
            log.write("/cmd_vel", t, msg.twist(t, 0.3, 0.2 if k < 20 else -0.2))
    res = segment_file(tmp_path / "m.mcap", out=tmp_path / "s.mcap", behaviors="avoid,wander,wall_attract")
    run = read_segmented(tmp_path / "s.mcap")
    assert np.isfinite(run.vectors).all()
    assert run.applicable[:, 0].all()  # the 1.5 m returns
    # commands held to each scan in time order, whatever order they were logged in
    heading = np.arctan2(run.demo[:, 1], run.demo[:, 0])
    assert (heading[1:20] > 0).all() and (heading[21:] < 0).all()
    assert not res.informative[0]  # no command yet at the first scan
