"""``lfdfuse.learn``: the one path teacher → demo → table, on short simulated demos."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lfdfuse.errors import ConfigError
from lfdfuse.evaluate.roundtrip import load_truth
from lfdfuse.learn import LearnOptions, demonstrate, learn, learn_run
from lfdfuse.segment.read import read_segmented
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world


@pytest.mark.parametrize("teacher", ["style", "table"])
def test_demonstrate_is_seeded_and_learn_reads_what_it_wrote(teacher: str, tmp_path: Path) -> None:
    truth, world = load_truth("tee-left")
    who = (Leg(None, "keep-left"),) if teacher == "style" else truth
    demos = [
        demonstrate(who, world=load_world(world), folder=tmp_path / k, name="d", duration_s=5.0, seed=3)
        for k in ("a", "b")
    ]
    for d in demos:
        assert d.raw.name == "d.mcap" and d.segmented.name == "d.seg.mcap"
        assert d.steps > 0 and d.duration_s == pytest.approx(5.0, abs=0.2) and d.wall_s > 0
    a, b = demos
    assert a.raw.read_bytes() == b.raw.read_bytes() and a.segmented.read_bytes() == b.segmented.read_bytes()
    run = read_segmented(a.segmented)
    if teacher == "table":
        assert run.names == truth.behaviors  # segmented with the teacher's own behaviours
    got = learn([a.segmented])
    same = learn_run(run, name=a.segmented.name)
    assert got.table == same.table and got.sources == ("d.seg.mcap",) and got.decisions == ()
    assert got.groups >= got.skipped >= 0


def test_learn_needs_a_demo_and_refuses_one_twice(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="at least one demonstration"):
        learn([])
    with pytest.raises(ConfigError, match="twice"):
        learn([tmp_path / "a.seg.mcap", tmp_path / "a.seg.mcap"], options=LearnOptions(subgoals=True))
    with pytest.raises(ConfigError, match="twice"):
        learn([tmp_path / "a.seg.mcap", tmp_path / "." / "a.seg.mcap"])


def test_a_demo_pooled_with_itself_keeps_its_weights_and_narrows(tmp_path: Path) -> None:
    """The same steps twice: the likelihood squared, so the rows' posteriors narrow (none widens)
    and their samples double; the first demo's weights are the rows' ``weights_before``."""
    d = demonstrate(
        (Leg(None, "keep-left"),), world=load_world("tee"), folder=tmp_path, name="d", duration_s=30.0, seed=1
    )
    twin = tmp_path / "twin.seg.mcap"
    twin.write_bytes(d.segmented.read_bytes())
    one, two = learn([d.segmented]).table, learn([d.segmented, twin]).table
    assert two.estimated_by["sources"] == ["d.seg.mcap", "twin.seg.mcap"]
    rows = {(s.name, r.bac): r for s in one.network.steps for r in s.fusion}
    ratios = []
    for s in two.network.steps:
        for r in s.fusion:
            alone = rows[(s.name, r.bac)]
            assert r.samples == 2 * (alone.samples or 0) and r.samples_added == alone.samples
            assert r.weights_before == alone.weights
            if r.std and alone.std:
                ratios += [r.std[b] / alone.std[b] for b in r.std if alone.std[b] > 1e-3]
    # rows the data limits narrow; a sloppy direction the likelihood leaves flat stays as wide
    assert ratios and float(np.median(ratios)) < 0.85 and max(ratios) < 1.15


def test_subgoals_without_a_track_is_a_config_error(tmp_path: Path) -> None:
    d = demonstrate(
        (Leg(None, "keep-left"),), world=load_world("tee"), folder=tmp_path, name="d", duration_s=5.0, seed=1
    )
    with pytest.raises(ConfigError, match="landmark track"):
        learn_run(read_segmented(d.segmented), options=LearnOptions(subgoals=True))
