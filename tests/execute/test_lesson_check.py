"""A correction's lesson checked in the demo's world (:mod:`lfdfuse.execute.lesson_check`).

The lessons are laws over which rows a correction re-weighted; which one is taken is checked
with the rollout replaced by a stand-in that says which start each table completes (the closed
loop itself: the ``corrections`` bench, seeds 1771, 1807 and 1935 in the README's measurement).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.execute import lesson_check
from lfdfuse.execute.check import DemoWorld, Drive
from lfdfuse.execute.lesson_check import Rereading, checked_lesson, lessons
from lfdfuse.network.landmark_goals import Landmark
from lfdfuse.network.table import FusionRow, FusionTable, Network, Step, named_leaf_steps
from lfdfuse.robot.pose import Pose
from lfdfuse.world.parse import World


def _row(bac: int, w: float) -> FusionRow:
    return FusionRow(
        bac=bac, weights={"a": w, "b": 1.0 - w}, std={"a": 0.1, "b": 0.1}, samples=40, fit_error_deg=5.0
    )


def _table(*steps: Step) -> FusionTable:
    return FusionTable(("a", "b"), {"a": 0.5, "b": 0.5}, Network("t", steps))


def _before() -> FusionTable:
    inner = (
        Step(
            "to-left-opening-1",
            None,
            (_row(1, 0.3), _row(3, 0.4)),
            landmark=Landmark("opening", "left", 1, 9.0),
        ),
        Step("turn-left", None, (_row(3, 0.2),), landmark=Landmark("turned", "left", angle_rad=1.4)),
        Step("reach-green", None, (_row(3, 0.5),)),
    )
    return _table(
        Step("reach-red", "red", (_row(3, 0.4), _row(5, 0.6))),
        Step("reach-green", "green", (), Network("reach-green", inner)),
        Step("reach-blue", "blue", (_row(3, 0.7),)),
    )


def _reweighted(table: FusionTable, names: set[str], w: float) -> FusionTable:
    """``table`` with every row of the leaves ``names`` re-weighted to ``w`` (and one row added)."""

    def walk(net: Network, prefix: str) -> Network:
        steps = []
        for s in net.steps:
            name = prefix + s.name
            if s.network is not None:
                s = replace(s, network=walk(s.network, name + "/"))
            elif name in names:
                s = replace(s, fusion=(*(_row(r.bac, w) for r in s.fusion), _row(7, w)))
            steps.append(s)
        return replace(net, steps=tuple(steps))

    return replace(table, network=walk(table.network, ""))


def _with_added_step(table: FusionTable) -> FusionTable:
    """``table`` with a new decision in reach-red: its leaves are new."""
    red = table.network.steps[0]
    inner = (
        Step("to-right-opening-2", None, (_row(3, 0.9),), landmark=Landmark("opening", "right", 2, 20.0)),
        Step("turn-right", None, (_row(3, 0.8),), landmark=Landmark("turned", "right", angle_rad=1.3)),
        replace(red, goal=None),
    )
    nested = Step("reach-red", "red", (), Network("reach-red", inner))
    return replace(table, network=replace(table.network, steps=(nested, *table.network.steps[1:])))


LEAVES = [
    "reach-red",
    "reach-green/to-left-opening-1",
    "reach-green/turn-left",
    "reach-green/reach-green",
    "reach-blue",
]


@settings(max_examples=40, deadline=None)
@given(
    st.sets(st.sampled_from(LEAVES), min_size=1),
    st.sets(st.sampled_from(["reach-red", "reach-green", "reach-blue"])),
    st.booleans(),
)
def test_a_smaller_lesson_keeps_every_row_outside_it_bit_for_bit(
    changed: set[str], taken_over: set[str], added: bool
) -> None:
    before = _before()
    whole = _reweighted(before, changed, 0.95)
    if added:
        whole = _with_added_step(whole)
    made = dict(lessons(before, whole, taken_over))
    assert next(iter(made)) == "whole" and made["whole"] is whole
    old = dict(named_leaf_steps(before))
    for name, table in made.items():
        assert table != before
        for leaf, step in named_leaf_steps(table):
            new = dict(named_leaf_steps(whole))[leaf]
            if leaf not in old:  # a step the correction added: its rows, in every lesson
                assert step.fusion == new.fusion
            elif name == "steps only" or (
                name == "where taken over" and leaf.split("/")[0] not in taken_over
            ):
                assert step.fusion == old[leaf].fusion
            else:
                assert step.fusion == new.fusion
            assert step.landmark == new.landmark
    tables = list(made.values())
    assert all(a != b for i, a in enumerate(tables) for b in tables[:i])


Drives = Callable[[FusionTable, World, Pose, float], Drive]


def _fake_rollout(completes: dict[tuple[tuple[int, int], float], bool | str]) -> Drives:
    """A drive that reaches every goal where ``completes[(table's weights, start x)]`` (the
    weights: of reach-blue's and of the turn's first row, in hundredths), with a wall hit where
    it is ``"!"``."""

    def drive(table: FusionTable, world: World, start: Pose, max_time_s: float) -> Drive:
        steps = dict(named_leaf_steps(table))
        key = tuple(
            round(steps[n].fusion[0].weights["a"] * 100) for n in ("reach-blue", "reach-green/turn-left")
        )
        got = completes[((key[0], key[1]), start.x)]
        return Drive(3 if got else 1, 1 if got == "!" else 0, np.zeros((1, 3)))

    return drive


def _mark(c: str) -> bool | str:
    """✓: every goal reached; ✗: not; !: every goal reached with a wall hit."""
    return "!" if c == "!" else c == "✓"


def _checked(monkeypatch: pytest.MonkeyPatch, outcome: dict[str, str]) -> lesson_check.CheckedLesson:
    """``outcome`` per table (``before``, ``whole``, ``where taken over``): ✓/✗/! per start
    (:func:`_mark`), the check's three starts, then the correction's."""
    before = _before()
    whole = _reweighted(before, {"reach-blue", "reach-green/turn-left"}, 0.95)
    w = {"before": (70, 20), "whole": (95, 95), "where taken over": (70, 95)}
    completes = {(w[k], float(x)): _mark(c) for k, marks in outcome.items() for x, c in enumerate(marks)}
    monkeypatch.setattr(lesson_check, "drive", _fake_rollout(completes))
    home = DemoWorld(None, Pose(0, 0, 0), np.zeros((2, 2)), 10.0, 3)  # type: ignore[arg-type]  # unused by the stand-in
    starts = [Pose(float(x), 0.0, 0.0) for x in range(3)]
    return checked_lesson(
        before, whole, taken_over={"reach-green"}, home=home, starts=starts, corrections=[Pose(3.0, 0, 0)]
    )


def test_the_whole_lesson_is_taken_where_it_keeps_every_start(monkeypatch: pytest.MonkeyPatch) -> None:
    got = _checked(monkeypatch, {"before": "✓✗✓✗", "whole": "✓✓✓✓", "where taken over": "✓✓✓✓"})
    assert got.lesson == "whole"


def test_a_lesson_that_breaks_a_start_the_table_completed_is_not_taken(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    got = _checked(monkeypatch, {"before": "✓✗✓✗", "whole": "✗✓✓✓", "where taken over": "✓✗✓✓"})
    assert got.lesson == "where taken over" and "completes" in got.why
    got = _checked(monkeypatch, {"before": "✓✗✓✗", "whole": "✗✓✓✓", "where taken over": "✓✗✗✓"})
    assert got.lesson is None and got.table == _before()


def test_a_lesson_that_does_not_complete_the_corrections_start_is_not_taken(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # each lesson keeps every check start (the whole one completes a start more), neither carries
    # the robot through from where the person corrected it
    got = _checked(monkeypatch, {"before": "✓✗✓✗", "whole": "✓✓✓✗", "where taken over": "✓✗✓✗"})
    assert got.lesson is None and got.table == _before()
    assert "no lesson completes the correction's start" in got.why
    # the same, but a smaller lesson completes it: that one is taken
    got = _checked(monkeypatch, {"before": "✓✗✓✗", "whole": "✓✓✓✗", "where taken over": "✓✗✓✓"})
    assert got.lesson == "where taken over"


def test_a_wall_hit_is_no_completed_run(monkeypatch: pytest.MonkeyPatch) -> None:
    # the correction's start reached every goal but hit a wall: a lesson must drive it clean
    got = _checked(monkeypatch, {"before": "✓✗✓!", "whole": "✓✓✓!", "where taken over": "✓✗✓✓"})
    assert got.lesson == "where taken over"
    # a check start the table before completed clean: a lesson that hits a wall there breaks it
    got = _checked(monkeypatch, {"before": "✓✗✓!", "whole": "!✓✓✓", "where taken over": "✓✗!✓"})
    assert got.lesson is None and "every lesson fails a check start" in got.why
    # a check start the table before drove through with a hit: a lesson must still reach every goal
    got = _checked(monkeypatch, {"before": "!✗✓!", "whole": "✗✓✓✓", "where taken over": "!✗✓✓"})
    assert got.lesson == "where taken over" and "1 of 3 check starts complete (1 before)" in got.why


#: each reading of :data:`~lfdfuse.execute.lesson_check.LADDER` a table of its own: its rows'
#: weights (reach-blue's, the turn's), in hundredths
READ = {r: (80 + k, 80 + k) for k, r in enumerate(lesson_check.LADDER)}
PERSON, EVEN, CORNERS = Rereading("person"), Rereading("even"), Rereading("pool", corners=True)


def _laddered(
    monkeypatch: pytest.MonkeyPatch,
    outcome: dict[str, str],
    read: dict[Rereading, str] | None = None,
    *,
    same: dict[Rereading, Rereading | None] | None = None,
) -> tuple[lesson_check.CheckedLesson, list[Rereading], int]:
    """As :func:`_checked`, with the tables of the correction read again too (``read``: ✓/✗/!
    per start for the tables of :data:`~lfdfuse.execute.lesson_check.LADDER`'s readings, every
    start failing where not given); also which readings were made, in order, and how many
    rollouts were driven. ``same``: a reading whose table is another's (None: the pooled whole
    one), as when the reading moves no row or step."""
    before = _before()
    whole = _reweighted(before, {"reach-blue", "reach-green/turn-left"}, 0.95)
    w = {"before": (70, 20), "whole": (95, 95), "where taken over": (70, 95)}
    completes = {(w[k], float(x)): _mark(c) for k, marks in outcome.items() for x, c in enumerate(marks)}
    for r, weights in READ.items():
        completes |= {(weights, float(x)): _mark(c) for x, c in enumerate((read or {}).get(r, "✗✗✗✗"))}
    stand_in = _fake_rollout(completes)
    driven = [0]

    def counted(table: FusionTable, world: World, start: Pose, max_time_s: float) -> Drive:
        driven[0] += 1
        return stand_in(table, world, start, max_time_s)

    monkeypatch.setattr(lesson_check, "drive", counted)
    made: list[Rereading] = []

    def reread(reading: Rereading) -> FusionTable:
        made.append(reading)
        if same is not None and reading in same:
            other = same[reading]
            if other is None:
                return whole
            reading = other
        return _reweighted(before, {"reach-blue", "reach-green/turn-left"}, READ[reading][0] / 100)

    home = DemoWorld(None, Pose(0, 0, 0), np.zeros((2, 2)), 10.0, 3)  # type: ignore[arg-type]  # unused by the stand-in
    starts = [Pose(float(x), 0.0, 0.0) for x in range(3)]
    got = checked_lesson(
        before,
        whole,
        taken_over={"reach-green"},
        home=home,
        starts=starts,
        corrections=[Pose(3.0, 0, 0)],
        reread=reread,
    )
    return got, made, driven[0]


#: neither pooled lesson completes the correction's start (the whole one keeps every check start)
POOLED_FAIL = {"before": "✓✗✓✗", "whole": "✓✓✓✗", "where taken over": "✓✗✓✗"}
OK, FAILS_START, MISSES_CORR = "✓✗✓✓", "✗✗✓✓", "✓✗✓✗"


def test_the_even_reading_is_tried_first_and_the_others_only_after_the_pooled_lessons(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    every = dict.fromkeys(READ, OK)
    got, made, _ = _laddered(
        monkeypatch, {"before": "✓✗✓✗", "whole": "✓✓✓✓", "where taken over": "✓✓✓✓"}, every
    )
    assert got.lesson == EVEN.name and got.reading == EVEN and made == [EVEN]
    # the even table misses the correction's start: the pooled lessons, and no other reading made
    later = {**every, EVEN: MISSES_CORR}
    got, made, _ = _laddered(
        monkeypatch, {"before": "✓✗✓✗", "whole": "✓✓✓✓", "where taken over": "✓✓✓✓"}, later
    )
    assert got.lesson == "whole" and got.reading is None and made == [EVEN]
    got, made, _ = _laddered(
        monkeypatch, {"before": "✓✗✓✗", "whole": "✗✓✓✓", "where taken over": "✓✗✓✓"}, later
    )
    assert got.lesson == "where taken over" and made == [EVEN]
    # no pooled lesson passes either: on down the readings
    got, made, _ = _laddered(monkeypatch, POOLED_FAIL, later)
    assert got.lesson == PERSON.name and made == [EVEN, PERSON]


def test_a_reading_that_is_a_pooled_lesson_is_tried_under_the_pooled_name(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # the person drove no row's worth of ticks in any row: the even table is the pooled whole one
    got, made, driven = _laddered(
        monkeypatch,
        {"before": "✓✗✓✗", "whole": "✓✓✓✓", "where taken over": "✓✓✓✓"},
        dict.fromkeys(READ, OK),
        same={EVEN: None},
    )
    assert got.lesson == "whole" and got.reading is None and made == [EVEN]
    assert driven == 3 + 4


def test_the_order_of_the_lessons() -> None:
    assert lesson_check.ORDER == (EVEN, "whole", "where taken over", "steps only", PERSON, CORNERS)
    assert set(lesson_check.LESSONS) <= set(lesson_check.ORDER)
    assert lesson_check.LADDER == (EVEN, PERSON, CORNERS)
    assert [r.name for r in lesson_check.LADDER] == [
        "whole, the person's ticks weighed even with the demo's",
        "whole, the person's ticks alone",
        "whole, the person's turns read at corners too",
    ]
    assert len({r.name for r in lesson_check.LADDER}) == len(lesson_check.LADDER)


def test_each_rung_is_taken_only_where_every_rung_before_it_is_not(monkeypatch: pytest.MonkeyPatch) -> None:
    ladder = lesson_check.LADDER
    for k, taken in enumerate(ladder):
        for miss in (FAILS_START, MISSES_CORR):
            # every rung before fails (a check start or the correction's), this one and those after pass
            read = {r: miss if n < k else OK for n, r in enumerate(ladder)}
            got, made, _ = _laddered(monkeypatch, POOLED_FAIL, read)
            assert got.lesson == taken.name and made == list(ladder[: k + 1]), (taken, miss, got)
            assert got.table != _before() and "the correction's start completes" in got.why
            assert got.describe().startswith(f"lesson checked in the demo's world: {taken.name}: ")
    got, made, _ = _laddered(monkeypatch, POOLED_FAIL, dict.fromkeys(ladder, MISSES_CORR))
    assert got.lesson is None and got.table == _before() and made == list(ladder)
    assert "no lesson completes the correction's start" in got.why
    # the same acceptance rule as the pooled lessons: none keeps every check start
    got, _, _ = _laddered(
        monkeypatch,
        {"before": "✓✗✓✗", "whole": "✗✓✓✓", "where taken over": "✗✗✓✓"},
        dict.fromkeys(ladder, FAILS_START),
    )
    assert got.lesson is None and "every lesson fails a check start" in got.why


def test_a_reading_that_moves_no_row_or_step_is_not_driven_again(monkeypatch: pytest.MonkeyPatch) -> None:
    ladder = lesson_check.LADDER
    _, made, driven = _laddered(monkeypatch, POOLED_FAIL, same=dict.fromkeys(ladder))
    assert made == list(ladder)
    # the table before from the check starts, each pooled lesson from every start; nothing more
    assert driven == 3 + 2 * 4
    # the turns read at corners add no decision: its table is the person-weighted one, tried before
    _, made, driven = _laddered(monkeypatch, POOLED_FAIL, same={CORNERS: PERSON})
    assert made == list(ladder)
    assert driven == 3 + 2 * 4 + 4 * (len(ladder) - 1)
