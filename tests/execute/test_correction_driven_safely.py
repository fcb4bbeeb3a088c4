"""A correction whose lesson holds only with the weights for unseen BACs made safe.

Generated world 3149 (a ring corridor, green at the end of a spur off its east side): the table
learned with sub-goals from the three-goal demo completes from three of four starts; from the
other it drives out of green's spur, up the east corridor, and turns back at its far corner: a
quarter of its ticks there are in BACs the reach-blue step never saw, where the step's default
weights (a fit to the teacher, ``avoid`` near 0) drive it. A scripted person
(:mod:`tests.support.corrections`) takes over as it comes out of the spur and drives the teacher's
path on; no lesson passes the lesson check (checked in the demo's world) until the first one
tried (the whole correction, the person's ticks weighed even with the demo's) is tried again with
its unseen BACs driven safely (``avoid`` at its default weight,
:func:`lfdfuse.network.table.safe_defaults`): the robot takes the corner and the table completes
from all four starts (measured; ~11 s).
"""

from __future__ import annotations

from pathlib import Path

from lfdfuse.execute import lesson_check
from lfdfuse.execute.lesson_check import SAFE
from lfdfuse.network.table import named_leaf_steps, safe_defaults
from tests.support.taught_again import teach_again

SEED = 3149


def test_a_lesson_is_taken_with_its_unseen_bacs_driven_safely(tmp_path: Path) -> None:
    w = teach_again(SEED, folder=tmp_path)
    assert w.failing is not None and w.corrected, w.row()
    (lesson,) = [v for v in w.verdicts if v.startswith("lesson checked")]
    first = lesson_check.LADDER[0].name
    assert lesson.startswith(f"lesson checked in the demo's world: {first}, {SAFE}:"), lesson
    assert w.table_before is not None and w.table_after is not None
    # the table taken is safe, and its weights for unseen BACs are not the table's before
    assert safe_defaults(w.table_after) == w.table_after
    assert w.table_before != safe_defaults(w.table_before)
    avoid = [
        s.default_weights.get("avoid", 0.0) for _, s in named_leaf_steps(w.table_after) if s.default_weights
    ]
    assert avoid and min(avoid) >= 1.0
    assert w.fixed and w.regressions == 0, w.row()
