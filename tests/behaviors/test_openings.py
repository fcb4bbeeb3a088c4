"""Openings as the robot senses them: mirror symmetry, hysteresis, and odometry that ignores the frame."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.behaviors.openings import (
    OpeningParams,
    OpeningSensor,
    OpeningTracker,
    ahead_range,
    odometry_increments,
    opening_onsets,
    sensed_onsets,
    side_openings,
)
from lfdfuse.behaviors.passing import PassedCounter, PassParams, passed_before
from lfdfuse.robot.readings import ScanGeometry

# a symmetric 181-beam laser: beam i and beam 180 − i are mirror images
GEOM = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 8.0)
seeds = st.integers(0, 2**32 - 1)


def _corridor_scans(rng: np.random.Generator, n: int) -> np.ndarray:
    """Scans of a corridor 1 m to each side, with openings (long returns) on random stretches."""
    r = np.full((n, 181), 1.0) / np.maximum(np.abs(np.sin(GEOM.angles)), 0.2)[None, :]
    for side in (slice(120, 175), slice(6, 61)):
        start = int(rng.integers(0, n))
        r[start : start + int(rng.integers(3, 15)), side] = 7.5
    return r


@settings(max_examples=12, deadline=None)
@given(seeds)
def test_a_mirrored_drive_sees_the_mirrored_openings(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 60
    scans = _corridor_scans(rng, n)
    step = np.full(n, 0.04)
    turn = rng.normal(0.0, 0.03, n)
    onsets, held = sensed_onsets(scans, GEOM, step, turn)
    m_onsets, m_held = sensed_onsets(scans[:, ::-1], GEOM, step, -turn)
    assert np.array_equal(onsets, m_onsets[:, ::-1])
    np.testing.assert_allclose(held, -m_held, atol=1e-12)


@settings(max_examples=40)
@given(st.lists(st.tuples(st.booleans(), st.booleans()), max_size=60))
def test_onsets_need_on_ticks_in_a_row_and_never_repeat_without_closing(
    flags: list[tuple[bool, bool]],
) -> None:
    p = OpeningParams()
    f = np.array(flags, dtype=bool).reshape(-1, 2)
    onsets = opening_onsets(f, np.zeros(len(f)), p)
    assert onsets.shape == f.shape
    for s in (0, 1):
        hits = np.nonzero(onsets[:, s])[0]
        for h in hits:
            assert h + 1 >= p.on_ticks and f[h + 1 - p.on_ticks : h + 1, s].all()
        for a, b in zip(hits, hits[1:], strict=False):
            assert (~f[a + 1 : b, s]).sum() >= p.off_ticks  # left behind in between


@settings(max_examples=40)
@given(st.lists(st.tuples(st.booleans(), st.booleans()), min_size=1, max_size=40))
def test_while_turning_no_side_opens(flags: list[tuple[bool, bool]]) -> None:
    tr = OpeningTracker()
    for f in flags:
        assert tr.update(np.array(f), turn_rad=math.radians(30.0)) == (False, False)


def test_a_scanner_that_misses_a_side_never_sees_an_opening_there() -> None:
    front = ScanGeometry(-math.radians(30), math.radians(1), 61, 8.0)
    assert not side_openings(np.full((3, 61), np.inf), front, OpeningParams()).any()
    # no return (inf, nan, 0, max range) reaches far
    for far in (np.inf, np.nan, 0.0, 8.0):
        assert side_openings(np.full((1, 181), far), GEOM, OpeningParams()).all()
    assert not side_openings(np.full((1, 181), 1.0), GEOM, OpeningParams()).any()


@settings(deadline=None)
@given(seeds, st.floats(-math.pi, math.pi), st.floats(-50, 50), st.floats(-50, 50))
def test_odometry_increments_ignore_where_the_path_is_and_add_up(
    seed: int, rot: float, dx: float, dy: float
) -> None:
    rng = np.random.default_rng(seed)
    steps = rng.uniform(0.0, 0.1, 30)
    turns = rng.uniform(-0.5, 0.5, 30)
    heading = np.cumsum(turns)
    pose = np.stack([np.cumsum(steps * np.cos(heading)), np.cumsum(steps * np.sin(heading)), heading], axis=1)
    c, s = math.cos(rot), math.sin(rot)
    moved = np.stack(
        [c * pose[:, 0] - s * pose[:, 1] + dx, s * pose[:, 0] + c * pose[:, 1] + dy, pose[:, 2] + rot], axis=1
    )
    d0, t0 = odometry_increments(pose)
    d1, t1 = odometry_increments(moved)
    np.testing.assert_allclose(d0, d1, atol=1e-9)
    np.testing.assert_allclose(t0, t1, atol=1e-9)
    assert d0[0] == 0.0 and t0[0] == 0.0
    np.testing.assert_allclose(t0[1:], turns[1:], atol=1e-12)  # turns within ±π are kept as they were
    np.testing.assert_allclose(d0[1:], steps[1:], atol=1e-9)  # straight chords of straight steps


def _drive(counter: PassedCounter, ticks: int, *, step_m: float = 0.1, turn_rad: float = 0.0) -> None:
    for _ in range(ticks):
        counter.update((False, False), step_m, turn_rad, 0.0)


def test_openings_driven_past_count_and_openings_turned_into_do_not() -> None:
    c = PassedCounter()
    c.update((True, False), 0.1, 0.0, 0.0)  # a junction on the left, driven past
    assert c.new == (True, False) and c.before == (0, 0)
    _drive(c, 30)
    assert c.before == (1, 0)
    c.update((True, False), 0.1, 0.0, 0.0)  # a corner on the left: the route turns into it
    _drive(c, 10, step_m=0.05, turn_rad=math.radians(9))
    _drive(c, 30)
    assert c.passed == [1, 0] and c.before == (1, 0)
    c.update((False, True), 0.1, 0.0, 0.0)  # an opening on the right, still undecided: counted
    c.update((False, False), 0.1, 0.0, 0.0)
    assert c.before == (1, 1)


def test_a_turn_begun_before_the_onset_is_a_turn_into_it() -> None:
    """The held heading, not the heading at the onset, is where the turn is measured from."""
    c = PassedCounter()
    c.update((False, True), 0.1, 0.0, held_turn_rad=-math.radians(30))  # already 30° to the right
    _drive(c, 5, turn_rad=-math.radians(4))
    _drive(c, 30)
    assert c.before == (0, 0)


def test_an_onset_flickering_at_an_openings_edge_is_that_opening() -> None:
    c = PassedCounter(PassParams(merge_m=1.5))
    c.update((True, False), 0.1, 0.0, 0.0)
    _drive(c, 5)
    c.update((True, False), 0.1, 0.0, 0.0)  # 0.6 m on: the same opening
    assert c.new == (False, False)
    _drive(c, 30)
    assert c.before == (1, 0)
    c.update((True, False), 0.1, 0.0, 0.0)  # 3 m on: the next one
    assert c.new == (True, False)


def _turn_on_the_spot(counter: PassedCounter, rad: float, ticks: int = 12) -> None:
    _drive(counter, ticks, step_m=0.0, turn_rad=rad / ticks)


def _into_a_dead_end_and_out(c: PassedCounter, depth_m: float) -> None:
    """Turn left into an opening met now, drive ``depth_m`` in, passing a niche on the right,
    turn round, and drive back out meeting openings on both sides (the niche, the dead end's
    mouth and the corridor it left, seen the other way), then turn left: on along the route."""
    c.update((True, False), 0.1, 0.0, 0.0)
    _drive(c, 10, step_m=0.05, turn_rad=math.radians(9))  # into it
    _drive(c, 10)
    c.update((False, True), 0.1, 0.0, 0.0)  # a niche in it, driven past
    _drive(c, int(depth_m / 0.1) - 11)
    _turn_on_the_spot(c, math.radians(180))
    c.update((True, False), 0.1, 0.0, 0.0)  # the niche, the other way
    assert c.leaving and c.new == (False, False)
    _drive(c, int(depth_m / 0.1) - 5)
    c.update((True, True), 0.1, 0.0, 0.0)  # the corridor it left, both ways
    assert c.new == (False, False)
    _drive(c, 10, step_m=0.05, turn_rad=math.radians(9))  # on along the route
    _drive(c, 20)


def test_openings_met_coming_back_out_of_a_dead_end_are_not_passed() -> None:
    """A robot that strays into a dead end the route passes by, turns round in it and comes back
    out: what it counted in there is undone, and nothing it meets on the way out counts; once back
    on the route, openings count again from where they were."""
    c = PassedCounter()
    c.update((False, True), 0.1, 0.0, 0.0)  # an opening on the right, driven past
    _drive(c, 30)
    assert c.before == (0, 1)
    _into_a_dead_end_and_out(c, 5.0)
    assert not c.leaving and c.before == (0, 1) and c.passed == [0, 1]
    c.update((False, True), 0.1, 0.0, 0.0)  # the next opening on the route: the 2nd on the right
    assert c.new == (False, True)
    _drive(c, 30)
    assert c.before == (0, 2)


def test_a_corridor_the_route_turns_into_and_follows_is_not_a_dead_end() -> None:
    """Turned round only past ``dead_end_m`` of the opening turned into: the openings met after
    are counted as any others (the way back along a corridor followed is a route too)."""
    c = PassedCounter()
    c.update((True, False), 0.1, 0.0, 0.0)  # a corner on the left: the route turns into it
    _drive(c, 10, step_m=0.05, turn_rad=math.radians(9))
    _drive(c, int(PassParams().dead_end_m / 0.1) + 5)
    c.update((False, True), 0.1, 0.0, 0.0)  # an opening on the right, driven past
    _drive(c, 30)
    _turn_on_the_spot(c, math.radians(180))
    assert not c.leaving
    c.update((True, False), 0.1, 0.0, 0.0)  # the same opening, now on the left
    assert c.new == (True, False)
    _drive(c, 30)
    assert c.before == (1, 1)


def test_a_driver_who_never_turns_round_counts_as_before_a_dead_end_rule() -> None:
    """The dead-end rule only undoes; without a turn round the counts are those of a counter
    that never turns round (a long straight drive, turns into corners and junctions)."""
    rng = np.random.default_rng(5)
    n = 400
    onsets = rng.random((n, 2)) < 0.03
    step = rng.uniform(0.05, 0.1, n)
    turn = rng.uniform(-0.06, 0.06, n)  # never more than 130° within 8 m in either sense
    before, new = passed_before(onsets, step, turn, np.zeros(n))
    off, off_new = passed_before(onsets, step, turn, np.zeros(n), PassParams(dead_end_m=0.0))
    assert np.array_equal(before, off) and np.array_equal(new, off_new)


def test_the_counter_over_a_log_is_the_counter_tick_by_tick() -> None:
    rng = np.random.default_rng(3)
    n = 200
    onsets = rng.random((n, 2)) < 0.05
    step = rng.uniform(0.0, 0.1, n)
    turn = rng.normal(0.0, 0.1, n)
    held = rng.normal(0.0, 0.3, n)
    before, new = passed_before(onsets, step, turn, held)
    c = PassedCounter()
    for i in range(n):
        c.update((bool(onsets[i, 0]), bool(onsets[i, 1])), float(step[i]), float(turn[i]), float(held[i]))
        assert tuple(before[i]) == c.before and tuple(new[i]) == c.new


def test_the_way_ahead_is_measured_along_the_held_heading() -> None:
    params = OpeningParams()
    r = np.full(GEOM.count, 8.0)
    r[np.abs(GEOM.angles) <= math.radians(12)] = 2.0  # a wall 2 m straight ahead
    assert ahead_range(r, GEOM, params) == 2.0
    assert ahead_range(r, GEOM, params, offset_rad=math.radians(45)) == 8.0  # held 45° to the left
    r[np.abs(GEOM.angles) <= math.radians(12)] = np.inf  # no return: far
    assert ahead_range(r, GEOM, params) == math.inf
    behind = ScanGeometry(math.pi / 2, math.pi / 180, 181, 8.0)  # a scanner that does not look ahead
    assert ahead_range(np.full(181, 1.0), behind, params) == math.inf


@settings(max_examples=25, deadline=None)
@given(seeds)
def test_the_sensors_short_scans_see_what_its_full_scans_see(seed: int) -> None:
    """The corridor and spin scans stop where the odometry passes their bound: the same holding,
    onsets and held headings tick by tick as the scans over the whole deques (which a sensor fed
    a negative step falls back to), through corridors, openings, stops and turns on the spot."""
    rng = np.random.default_rng(seed)
    n = 400
    r = _corridor_scans(rng, n)
    for start in rng.integers(0, n - 30, 4):  # rooms: no walls abeam
        r[start : start + rng.integers(5, 30)] = 6.0
    step = rng.uniform(0.0, 0.08, n)
    step[rng.uniform(size=n) < 0.15] = 0.0  # standing, turning on the spot
    turn = rng.normal(0.0, 0.05, n)
    turn[rng.uniform(size=n) < 0.08] = rng.choice([0.5, -0.5])
    short, full = OpeningSensor(GEOM), OpeningSensor(GEOM)
    full._ordered = False  # as after a negative step: every scan over the whole deque
    for i in range(n):
        assert short.update(r[i], float(step[i]), float(turn[i])) == full.update(
            r[i], float(step[i]), float(turn[i])
        )
        assert (short.holding, short.held_turn_rad, short.ahead_m) == (
            full.holding,
            full.held_turn_rad,
            full.ahead_m,
        )
        assert short._ordered
