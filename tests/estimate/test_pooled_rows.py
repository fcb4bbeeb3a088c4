"""How a correction's ticks weigh in a pooled row (:mod:`lfdfuse.estimate.pooled_rows`): laws
over the parts of one row (demos' and corrections' steps) drawn by hypothesis."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.pooled_rows import WEIGHINGS, Weighing, evenly, weighed

MIN = 30


@st.composite
def row_parts(draw: st.DrawFn) -> tuple[list[tuple[int, np.ndarray]], set[int]]:
    """One row's parts: demo 0, maybe a second teacher's demo, and one or two corrections (a
    demo may come in several parts, as a sub-step's parts do), each a sorted run of steps; every
    step in them distinct and in order, so a step tells its place among them all."""
    demos = draw(st.lists(st.sampled_from([0, 1, 2, 3]), min_size=1, max_size=5))
    corrections = draw(st.sets(st.sampled_from([2, 3]), min_size=1))
    parts = []
    at = 0
    for e in demos:
        n = draw(st.integers(0, 400))
        step = draw(st.integers(1, 3))
        parts.append((e, np.arange(at, at + step * n, step)))
        at += step * n + draw(st.integers(0, 50))
    return parts, corrections


def _count(parts: list[tuple[int, np.ndarray]], which: set[int], inside: bool) -> int:
    return sum(len(t) for e, t in parts if (e in which) == inside)


@settings(max_examples=200, deadline=None)
@given(row_parts())
def test_pooled_the_parts_are_as_they_are(drawn: tuple[list[tuple[int, np.ndarray]], set[int]]) -> None:
    parts, corrections = drawn
    got = weighed(parts, corrections=corrections, weighing="pool", min_samples=MIN)
    assert len(got) == len(parts)
    assert all(a == c and b is d for (a, b), (c, d) in zip(got, parts, strict=True))


@settings(max_examples=200, deadline=None)
@given(row_parts(), st.sampled_from(WEIGHINGS))
def test_a_row_the_person_drove_too_little_in_is_pooled_whatever_the_weighing(
    drawn: tuple[list[tuple[int, np.ndarray]], set[int]], weighing: Weighing
) -> None:
    parts, corrections = drawn
    got = weighed(parts, corrections=corrections, weighing=weighing, min_samples=MIN)
    if _count(parts, corrections, True) < MIN:
        assert [(e, t.tolist()) for e, t in got] == [(e, t.tolist()) for e, t in parts]


@settings(max_examples=300, deadline=None)
@given(row_parts())
def test_even_keeps_as_many_demo_steps_as_person_ticks_evenly_spread(
    drawn: tuple[list[tuple[int, np.ndarray]], set[int]],
) -> None:
    parts, corrections = drawn
    person = _count(parts, corrections, True)
    demo = _count(parts, corrections, False)
    got = weighed(parts, corrections=corrections, weighing="even", min_samples=MIN)
    if person < MIN:
        return
    # the person's ticks as they were, in order
    mine = [(e, t.tolist()) for e, t in parts if e in corrections]
    assert [(e, t.tolist()) for e, t in got if e in corrections] == mine
    # the demos' steps: the person's count of them (all where fewer), each part a subset of the
    # demo's own part there, the parts in order
    assert _count(got, corrections, False) == min(demo, person)
    src = iter((e, t) for e, t in parts)
    for e, t in got:
        assert any(e == f and np.isin(t, u).all() for f, u in src)
    # spread evenly over the demos' steps in order: first and last kept, gaps within one
    whole = np.concatenate([t for e, t in parts if e not in corrections] or [np.zeros(0, int)])
    kept = np.concatenate([t for e, t in got if e not in corrections] or [np.zeros(0, int)])
    places = np.searchsorted(whole, kept)
    assert np.array_equal(whole[places], kept) and np.all(np.diff(places) > 0)
    if 1 < len(places) < len(whole):
        gaps = np.diff(places)
        assert places[0] == 0 and places[-1] == len(whole) - 1
        assert gaps.max() - gaps.min() <= 1


@settings(max_examples=200, deadline=None)
@given(row_parts())
def test_person_keeps_the_persons_ticks_alone(drawn: tuple[list[tuple[int, np.ndarray]], set[int]]) -> None:
    parts, corrections = drawn
    got = weighed(parts, corrections=corrections, weighing="person", min_samples=MIN)
    if _count(parts, corrections, True) >= MIN:
        assert [(e, t.tolist()) for e, t in got] == [(e, t.tolist()) for e, t in parts if e in corrections]


@given(st.integers(0, 2000), st.integers(0, 2000))
def test_evenly_is_n_distinct_positions_first_and_last_kept(n_of: int, n: int) -> None:
    got = evenly(n_of, n)
    assert len(got) == min(max(n, 0), n_of)
    assert np.all(np.diff(got) > 0) and (len(got) == 0 or (got[0] >= 0 and got[-1] < n_of))
    if 1 < n < n_of:
        assert got[0] == 0 and got[-1] == n_of - 1
        gaps = np.diff(got)
        assert gaps.max() - gaps.min() <= 1


def test_an_unknown_weighing_is_one_line_error() -> None:
    from lfdfuse.estimate.pooled_subgoals import pool_subgoals

    with pytest.raises(ConfigError, match="weighing 'heavy': one of pool, even, person"):
        pool_subgoals(
            first=None,  # type: ignore[arg-type]  # refused before any is read
            first_name="demo",
            paper=None,  # type: ignore[arg-type]
            table=None,  # type: ignore[arg-type]
            decisions=(),
            others=(),
            opts=None,  # type: ignore[arg-type]
            weighing="heavy",  # type: ignore[arg-type]
        )
