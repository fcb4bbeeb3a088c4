"""A forced turn whose goal lies far beyond it: read within the turn's window, never past it.

Generated world 3526's three-goal demo: in the re-reading that sub-goal repair makes, a turn the
teacher took (forced: a decision wherever it reads as one) turned less than a decision's least
turn from the heading the sectors held, and its goal came 60 s later. The turn, as far as the
goal cut it short, was read at the goal — past the turn's window, where the window's headings
end (an index error). It is read within the window: less than a decision's least turn, so no
decision there; learning the demo finds the others (measured; ~11 s).
"""

from __future__ import annotations

from pathlib import Path

from lfdfuse import learn
from lfdfuse.segment.decisions import DecisionParams
from tests.support.generated import THREE_GOALS
from tests.support.generated_worlds import generate_offroute

SEED = 3526


def test_a_forced_turn_whose_goal_lies_beyond_its_window_is_read_within_it(tmp_path: Path) -> None:
    world = generate_offroute(SEED)
    demo = learn.demonstrate(
        THREE_GOALS, world=world, folder=tmp_path, name=f"{world.name}-demo", duration_s=900.0, seed=1
    )
    res = learn.learn([demo.segmented], options=learn.LearnOptions(subgoals=True))
    p = DecisionParams()
    assert res.decisions, "the demo's turn-offs are decisions"
    for d in res.decisions:
        assert p.min_angle_rad <= d.angle_rad <= p.max_angle_rad, d
        assert d.onset <= d.turn_end
