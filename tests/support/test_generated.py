"""Sub-goals that carry (issue 21): held-apart generated off-route worlds, closed loop.

The full measure (20 held-apart worlds, 3 perturbed starts each, with and without sub-goals) is
the ``generated`` bench (``make bench``). On seeds 1020-1039 the chosen decision parameters
completed 38/60 runs with sub-goals and 21/60 without: below issue 21's 90 %. Here, as a guard
of what does carry, two of those worlds whose spur the learned network takes only through its
sub-goals or takes with them as without (1022: 0/3 without, 3/3 with; 1025: 3/3 and 3/3), from
two perturbed starts each (203 s on two cores shared with other runs).
"""

from __future__ import annotations

from pathlib import Path

from tests.support.generated import completion, run_generated
from tests.support.generated_worlds import HELD_APART_SEEDS

#: held-apart worlds, never tuned on: green at the end of a spur off the 2nd right opening after
#: red (1022), off the 1st left one (1025)
WORLDS = (1022, 1025)
#: issue 21's done-when: the task with sub-goals completes at least this share of the runs
THRESHOLD = 0.9


def test_where_sub_goals_carried_in_held_apart_worlds_they_still_do(tmp_path: Path) -> None:
    assert all(seed in HELD_APART_SEEDS for seed in WORLDS)
    outcomes = [run_generated(seed, folder=tmp_path / str(seed), starts=2) for seed in WORLDS]
    assert all(o.demo_completed for o in outcomes)
    assert all(o.landmarks["subgoals"] for o in outcomes), "both spurs are decision points"
    sub, plain = completion(outcomes, "subgoals"), completion(outcomes, "reactive")
    assert sub.runs == plain.runs == 2 * len(WORLDS)
    rows = [r for o in outcomes for r in o.rows]
    assert sub.rate is not None and sub.rate >= THRESHOLD, rows
    assert plain.completed < sub.completed, rows  # 1022's spur is missed without sub-goals
