"""A real person's steering (TurtleBot 4, keyboard teleop) explained by the learned fusion.

Skipped without the shared real data (../shared/realdata or $LFDFUSE_SHARED).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.evaluate.batch import LogJob, evaluate_log
from lfdfuse.evaluate.holdout import Evaluation, evaluate
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
KEYBOARD_LOGS = {"turtlebot": TURTLEBOT, "neato": NEATO}


@pytest.fixture(scope="module")
def keyboard(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Evaluation]:
    """Each real keyboard log as a user scores it: `import`, `segment` (lag and command model
    auto), `evaluate` (last 30 % held out, seed 0)."""
    if not all(p.exists() for p in KEYBOARD_LOGS.values()):
        pytest.skip("shared real data not present")
    out = {}
    for name, src in KEYBOARD_LOGS.items():
        folder = tmp_path_factory.mktemp(name)
        import_log(src, out=folder / "demo.mcap")
        seg = segment_file(folder / "demo.mcap", out=folder / "demo.seg.mcap", lag_s=None)
        out[name] = evaluate(read_segmented(seg.out), holdout=0.3)
    return out


def test_turtlebot_keyboard_log_is_discrete_and_scored_by_its_decisions(
    keyboard: dict[str, Evaluation],
) -> None:
    """A keyboard log is read as a person's decisions (the discrete command model) at
    the lag that explains its presses; every method's command accuracy is scored beside
    'straight' (the most common command) and 'previous'."""
    ev = keyboard["turtlebot"]
    assert ev.commands == "discrete" and ev.test_decisions is not None and ev.test_decisions >= 10
    acc = {k: v.command_accuracy for k, v in ev.methods.items()}
    assert all(a is not None and 0.0 <= a <= 1.0 for a in acc.values()), acc
    m = {k: v.heading_error_deg for k, v in ev.methods.items()}
    assert m["fused"] <= m["oracle"] + 6.0, m
    turn = {k: v.turning_error_deg for k, v in ev.methods.items()}
    assert turn["fused"] < turn["straight"], turn
    d = ev.to_dict()
    assert "command_accuracy" in d["methods"]["straight"] and d["commands"] == "discrete"


def test_the_learned_fusion_explains_a_person_at_a_keyboard(keyboard: dict[str, Evaluation]) -> None:
    """On real keyboard logs the fused network, read as key presses, predicts the person's heading
    better than driving straight on and comes near the oracle, as far as a 70/30 split allows.

    TurtleBot (lag 0.8 s, 21 held-out decisions of which 5 are stops): fused errs 9.4° on the
    held-out steps to straight's 12.0° and 28.2° on the 23 turning steps to straight's 38.2°; 1.0°
    above the oracle's 8.4°. Its key response (σ 54°: the fused heading says little about the key
    beyond the person's liking for forward) predicts 9 commands, as many as 'straight' (the bin of
    the fused heading predicted 10).
    Neato (lag 1.0 s, held-out part one forward command, then stops): 26.7°; the oracle, reading
    the held-out forward decisions in the keyboard's command set (forward's bin ±45°), is 0°
    (in the held-out part's own one-command set it would be the prior). No weights that put
    18 of the 20 training decisions in their bins come within 20° of it on the held-out steps:
    counting the 10 s turn in place once gives 14.2° but costs the TurtleBot 2.4°, and no
    validation inside the training part prefers that, so the Neato's fused error stays well above
    its oracle on this split.
    """
    tb = keyboard["turtlebot"].methods
    assert tb["fused"].command_accuracy is not None and tb["straight"].command_accuracy is not None
    assert tb["fused"].command_accuracy >= tb["straight"].command_accuracy
    assert tb["fused"].heading_error_deg < tb["straight"].heading_error_deg - 2.0
    assert tb["fused"].turning_error_deg < tb["straight"].turning_error_deg
    assert tb["fused"].heading_error_deg <= tb["oracle"].heading_error_deg + 2.0
    ne = keyboard["neato"].methods
    assert keyboard["neato"].commands == "discrete" and keyboard["neato"].turning_steps == 0
    # the oracle reads the held-out forward decisions in the keyboard's command set: all forward
    assert ne["oracle"].heading_error_deg < 8.0
    assert ne["fused"].heading_error_deg < 30.0
    assert ne["fused"].command_accuracy is not None and ne["straight"].command_accuracy is not None
    assert ne["fused"].command_accuracy > ne["straight"].command_accuracy


GGRICE = SHARED / "realdata" / "human" / "GGRice__comprobo_warmup_project" / "bags"
KFOLD_KEYBOARDS = {
    "ggrice": GGRICE / "rosbag_first_test_2018-09-11-15-04-53.bag",
    "neato": NEATO,
}


@pytest.mark.parametrize("name", sorted(KFOLD_KEYBOARDS))
def test_keyboard_drives_read_as_key_presses_beat_driving_straight_on(name: str) -> None:
    """Two people at a Neato's keyboard, scored as ``lfdfuse evaluate LOG`` does (import, segment,
    blocked 5-fold): the fused network read as key presses errs less than 'straight' on the
    held-out steps (GGRice 18.7° to 24.7°, Neato 23.3° to 36.0°; read as the fused vector's own
    heading, 29.0° and 31.9°), on the turns, and predicts as many keys (48 % to 35 %, 46 % to 14 %)."""
    src = KFOLD_KEYBOARDS[name]
    if not src.exists():
        pytest.skip("shared real data not present")
    ev = evaluate_log(LogJob(str(src), str(src), None, 0)).evaluation
    assert ev.commands == "discrete" and ev.split == "kfold" and ev.keys is not None
    m = ev.methods
    assert m["fused"].heading_error_deg <= m["straight"].heading_error_deg - 5.0, m
    assert m["fused"].turning_error_deg < m["straight"].turning_error_deg, m
    assert m["fused"].heading_error_deg <= m["oracle"].heading_error_deg + 10.0, m
    f, s = m["fused"].command_accuracy, m["straight"].command_accuracy
    assert f is not None and s is not None and f >= s + 0.1, (f, s)
