"""A real person's steering (TurtleBot 4, keyboard teleop) explained by the learned fusion.

Skipped without the shared real data (../shared/realdata or $LFDFUSE_SHARED).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.evaluate.holdout import evaluate
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from lfdfuse.sources.importers.convert import import_log
from tests.conftest import SHARED

TURTLEBOT = SHARED / "realdata" / "ros2" / "macfirst_floor_take_2.mcap"


@pytest.mark.parametrize("lag_s", [0.0, 0.3])
def test_turtlebot_holdout_fused_is_near_the_oracle_and_beats_arbitration(
    tmp_path: Path, lag_s: float
) -> None:
    if not TURTLEBOT.exists():
        pytest.skip("shared real data not present")
    demo = tmp_path / "tb.mcap"
    import_log(TURTLEBOT, out=demo)
    seg = segment_file(demo, out=tmp_path / "tb.seg.mcap", lag_s=lag_s, measure_lag=False)
    # the continuous command model's claim (the discrete model's is below)
    ev = evaluate(read_segmented(seg.out), holdout=0.3, opts=EstimateOptions(commands="continuous"))
    m = {k: v.heading_error_deg for k, v in ev.methods.items()}
    assert m["fused"] <= m["oracle"] + 6.0, m
    assert m["fused"] < m["arbitration"], m
    # where the person turned, the sensors explain it better than driving straight on
    turn = {k: v.turning_error_deg for k, v in ev.methods.items()}
    assert turn["fused"] < turn["straight"], turn


NEATO = SHARED / "realdata" / "ros1" / "neato-keyboard-middle.bag"


def test_turtlebot_keyboard_log_is_discrete_and_scored_by_its_decisions(tmp_path: Path) -> None:
    """Issue 19: a keyboard log is read as a person's decisions (the discrete command model) at
    the lag that explains its presses; every method's command accuracy is scored beside
    'straight' (the most common command) and 'previous'."""
    if not TURTLEBOT.exists():
        pytest.skip("shared real data not present")
    demo = tmp_path / "tb.mcap"
    import_log(TURTLEBOT, out=demo)
    seg = segment_file(demo, out=tmp_path / "tb.seg.mcap", lag_s=None)
    run = read_segmented(seg.out)
    assert run.metadata["segment_commands"] == "discrete"
    ev = evaluate(run, holdout=0.3)
    assert ev.commands == "discrete" and ev.test_decisions is not None and ev.test_decisions >= 10
    acc = {k: v.command_accuracy for k, v in ev.methods.items()}
    assert all(a is not None and 0.0 <= a <= 1.0 for a in acc.values()), acc
    m = {k: v.heading_error_deg for k, v in ev.methods.items()}
    assert m["fused"] <= m["oracle"] + 6.0, m
    turn = {k: v.turning_error_deg for k, v in ev.methods.items()}
    assert turn["fused"] < turn["straight"], turn
    d = ev.to_dict()
    assert "command_accuracy" in d["methods"]["straight"] and d["commands"] == "discrete"
