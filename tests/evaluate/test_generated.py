"""Sub-goals that carry (issue 21): a held-apart generated off-route world, closed loop.

The full measure (the first 20 held-apart worlds, 3 perturbed starts each, with and without
sub-goals) is the ``generated`` bench; here the first held-apart world from two perturbed starts.
"""

from __future__ import annotations

from pathlib import Path

from lfdfuse.evaluate.generated import completion, run_generated
from lfdfuse.world.generate import HELD_APART_SEEDS


def test_sub_goals_complete_the_task_from_perturbed_starts_in_a_held_apart_world(tmp_path: Path) -> None:
    outcome = run_generated(HELD_APART_SEEDS[0], folder=tmp_path, starts=2)
    assert outcome.demo_completed
    sub, plain = completion([outcome], "subgoals"), completion([outcome], "reactive")
    assert sub.runs == plain.runs == 2
    assert sub.completed == 2 and sub.completed >= plain.completed, outcome.rows
