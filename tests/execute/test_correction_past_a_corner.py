"""A correction's turn into a spur just past a corner: a decision on the lesson ladder's corners rung.

Generated world 2541 (a ring corridor, the green target at the end of a spur off its outer wall
a few metres past a corner): the table learned with sub-goals from the three-goal demo drives
round the ring past the spur from all four starts — the teacher cut into the spur, so its demo
names no opening there, and the camera never sees the target from the ring. A scripted person
(:mod:`tests.support.corrections`) takes over before the spur and drives the teacher's path into
it. In the correction, sensed with the sectors held at the heading from before the corner, the
spur reads as a corner (the way ahead and the other side closed), and a teacher's turn into a
corner is no decision: there was no other way. Read so, the correction re-weights rows only and
no lesson completes its start (the pooled ones, nor the person-weighted ones); the corners rung
reads the person's turns at corners too (their network drove on: there was another way), the
turn becomes a decision, and the table completes from all four starts (measured; ~11 s).
"""

from __future__ import annotations

from pathlib import Path

from tests.support.taught_again import teach_again

SEED = 2541


def test_a_corrections_turn_into_a_spur_past_a_corner_is_taken_on_the_corners_rung(tmp_path: Path) -> None:
    w = teach_again(SEED, folder=tmp_path)
    assert w.failing is not None and w.corrected, w.row()
    (lesson,) = [v for v in w.verdicts if v.startswith("lesson checked")]
    assert lesson.startswith(
        "lesson checked in the demo's world: whole, the person's turns read at corners too:"
    )
    added = [v for v in w.verdicts if v.startswith("added") and "correction" in v]
    assert added, w.verdicts
    assert w.fixed and w.regressions == 0, w.row()
