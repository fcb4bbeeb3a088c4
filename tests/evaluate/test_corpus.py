"""A corpus of logs: every log `import` reads found under folders, fused compared across logs, and
the real command on real people's drives (skipped without the shared real data)."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.errors import LogError
from lfdfuse.evaluate.corpus import compare, expand_logs, find_logs
from lfdfuse.evaluate.folds import KFOLD_METHODS
from tests.conftest import SHARED

REAL = SHARED / "realdata"
HUMAN = REAL / "human"
#: a rosbag2 folder (27 informative decisions), and two drives too short to score (9 and 16)
ROSBAG2 = HUMAN / "Cbabe__NeatoWarmUpProject" / "Bags" / "teleop_bag_v2"
SHORT = HUMAN / "yycho0108__comprobo_warmup_project" / "warmup_project" / "bags" / "test_drive.bag"
WALL = HUMAN / "Brooks-Willis__Comprobo_Mobile_Project" / "drive3_a_wall.bag"

needs_real = pytest.mark.skipif(not HUMAN.is_dir(), reason="shared real data not present")


@needs_real
def test_every_log_import_reads_is_found_and_a_rosbag2_folder_is_one_log_whatever_its_name(
    tmp_path: Path,
) -> None:
    (tmp_path / "drives" / "bags").mkdir(parents=True)
    (tmp_path / "drives" / "bags" / "run.bag").symlink_to(ROSBAG2)  # a rosbag2 folder named *.bag
    (tmp_path / "drives" / "short.bag").symlink_to(SHORT)  # a ROS 1 bag
    (tmp_path / "drives" / "notes.txt").write_text("not a log\n")
    (tmp_path / "drives" / ".hidden").mkdir()
    (tmp_path / "drives" / ".hidden" / "x.bag").symlink_to(WALL)
    found = find_logs(tmp_path / "drives")
    assert found == [tmp_path / "drives" / "bags" / "run.bag", tmp_path / "drives" / "short.bag"]
    # the simulated corpus's layout: a folder `bags/test_drive.bag/` holding metadata.yaml and a .db3
    sim = REAL / "simulated"
    assert [p.name for p in find_logs(sim)] == ["test_drive.bag"]
    assert find_logs(sim)[0].is_dir()
    # the 11 drives of human/: one rosbag2 folder and ten ROS 1 bags
    human = find_logs(HUMAN)
    assert len(human) == 11 and sum(p.is_dir() for p in human) == 1
    logs, walked = expand_logs([ROSBAG2, SHORT])
    assert logs == [ROSBAG2, SHORT] and not walked  # a bag given by name is that log


def test_a_folder_without_a_log_is_one_error(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(LogError, match="no log lfdfuse can import"):
        expand_logs([tmp_path / "empty"])


@given(st.lists(st.tuples(st.floats(0, 90), st.floats(0, 90)), min_size=1, max_size=30), st.integers(0, 99))
@settings(max_examples=60, deadline=None)
def test_the_comparison_counts_wins_and_its_interval_holds_the_median(
    pairs: list[tuple[float, float]], seed: int
) -> None:
    fused, other = [p[0] for p in pairs], [p[1] for p in pairs]
    c = compare(fused, other, seed=seed, resamples=500)
    d = np.array(fused) - np.array(other)
    assert c["of"] == len(pairs) and c["better"] == int((d < 0).sum()) and c["ties"] == int((d == 0).sum())
    assert math.isclose(c["median_diff"], float(np.median(d)), abs_tol=1e-3)
    lo, hi = c["ci95"]
    assert lo - 1e-3 <= c["median_diff"] <= hi + 1e-3
    assert compare(fused, other, seed=seed, resamples=500) == c  # seeded: the same interval


def test_the_comparison_skips_logs_without_both_scores() -> None:
    c = compare([1.0, None, 3.0, float("nan")], [2.0, 5.0, None, 1.0], seed=0)
    assert c["of"] == 1 and c["better"] == 1 and c["median_diff"] == -1.0
    acc = compare([0.5, 0.4], [0.4, 0.4], seed=0, higher_is_better=True)
    assert acc["better"] == 1 and acc["ties"] == 1
    assert compare([], [], seed=0)["ci95"] is None


@needs_real
def test_evaluate_a_folder_of_real_drives_end_to_end(tmp_path: Path) -> None:
    """The real command on a folder of three real drives (a rosbag2 folder, two drives too short
    to score): a row per log, the reasons in the rows, the comparison across logs, exit 1 for the
    logs that could not be scored, never a traceback."""
    corpus = tmp_path / "corpus"
    (corpus / "bags").mkdir(parents=True)
    (corpus / "bags" / "teleop").symlink_to(ROSBAG2)
    (corpus / "short.bag").symlink_to(SHORT)
    (corpus / "wall.bag").symlink_to(WALL)
    out = tmp_path / "corpus.json"
    res = CliRunner(env={"COLUMNS": "250"}).invoke(app, ["evaluate", str(corpus), "--json", str(out)])
    assert res.exit_code == 1, res.output  # two logs could not be scored (the contract's exit code)
    assert "Traceback" not in res.output
    text = res.output
    assert "3 logs" in text and "2 not scored" in text
    for why in ("9 informative", "16 informative"):
        assert f"not scored: too few decisions to score: {why}" in text, text
    data = json.loads(out.read_text())
    assert [os.path.basename(e["path"]) for e in data["logs"]] == ["teleop", "short.bag", "wall.bag"]
    scored = data["logs"][0]
    assert scored["prepared"] == ["import", "segment"] and scored["split"] == "kfold"
    assert list(scored["methods"]) == list(KFOLD_METHODS)
    assert scored["informative_decisions"] >= 20 and scored["folds"] == 5
    assert all(len(m["fold_errors_deg"]) == 5 for m in scored["methods"].values())
    assert "too few decisions" in data["logs"][1]["error"]
    summary = data["summary"]
    assert summary["logs"] == 1 and summary["failed"] == 2
    assert set(summary["compare"]) == set(KFOLD_METHODS) - {"fused"}
    bc = summary["compare"]["bc"]["heading_error_deg"]
    fused, clone = (
        scored["methods"]["fused"]["heading_error_deg"],
        scored["methods"]["bc"]["heading_error_deg"],
    )
    assert bc["of"] == 1 and math.isclose(bc["median_diff"], fused - clone, abs_tol=2e-3)
    for name in ("fused", "bc", "straight", "oracle (floor)"):
        assert name in text
