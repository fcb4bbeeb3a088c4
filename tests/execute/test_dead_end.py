"""A robot that strays into a dead end and comes back out still turns off at the teacher's opening.

Generated world 1720 (held apart from the ``generated`` bench): after red the teacher drives
past two openings on the right and a dead-end alcove on the left, follows the corridor round a
corner and turns into the 3rd opening on the right, green's spur. From a perturbed start the
robot learned with sub-goals is drawn into the alcove, turns round in it and comes back out.
Counted as openings passed, the alcove's mouth and the corridor seen from inside it made the
"3rd opening on the right" of the decision, and the table turned right, back the way it came;
the passed count undoes the excursion (:class:`lfdfuse.behaviors.passing.PassedCounter`), and the
task completes. Closed loop, one world, one start (about 25 s).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from lfdfuse import learn
from lfdfuse.behaviors.passing import PassedCounter
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.execute.starts import perturbed_starts
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.read import read_segmented
from tests.support.generated import THREE_GOALS, TIME_FACTOR
from tests.support.generated_worlds import generate_offroute
from tests.support.offroute import OffRouteCase, run_starts

SEED = 1720
START = 1  # of the bench's 4 perturbed starts: the one drawn into the alcove


def test_a_dead_end_strayed_into_and_left_does_not_count_toward_the_decision(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    world = generate_offroute(SEED)
    demo = learn.demonstrate(THREE_GOALS, world=world, folder=tmp_path, name="demo", duration_s=900.0, seed=1)
    run = read_segmented(demo.segmented)
    assert [s.target for s in run.segments if s.target is not None] == [leg.target for leg in THREE_GOALS]
    table = learn.learn([demo.segmented], options=learn.LearnOptions(EstimateOptions(), subgoals=True)).table
    green = table.network.steps[1].network
    assert green is not None and green.steps[0].landmark is not None
    assert green.steps[0].landmark.to_dict()["opening"] == "right" and green.steps[0].landmark.nth == 3
    max_t = float(math.ceil(TIME_FACTOR * demo.duration_s / 10.0) * 10.0)
    case = OffRouteCase(world, THREE_GOALS, max_t, tuple(str(leg.target) for leg in THREE_GOALS))
    starts = perturbed_starts(world, Pose(*world.start), n=4, rng=np.random.default_rng(SEED))
    start = [starts[START].as_tuple()]

    left: list[bool] = []
    undo = PassedCounter._dead_end

    def watched(self: PassedCounter) -> None:
        undo(self)
        if self.leaving:
            left.append(True)

    monkeypatch.setattr(PassedCounter, "_dead_end", watched)
    rows = run_starts(table, case, starts=start, folder=tmp_path, label="robot")
    assert left, "the robot strays into the alcove and comes back out of it"
    assert rows[0]["completed"], rows

    # counting the openings met on the way out, the same table turns back before the corner
    monkeypatch.setattr(PassedCounter, "_dead_end", lambda self: None)
    rows = run_starts(table, case, starts=start, folder=tmp_path, label="counted")
    assert not rows[0]["completed"] and rows[0]["reached"] == "red", rows
