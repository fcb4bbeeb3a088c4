"""Landmark postconditions: their YAML form round-trips, left and right mirror, more seen is more met."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.errors import ConfigError
from lfdfuse.network.landmark_goals import Cues, Landmark, Progress

sides = st.sampled_from(["left", "right"])
lags = st.none() | st.integers(1, 10_000).map(lambda mm: mm / 1000)
openings = st.builds(
    lambda side, nth, odo, lag: Landmark("opening", side, nth, odo, lag_m=lag),
    sides,
    st.integers(1, 1000),
    st.none() | st.integers(0, 10**6 - 1).map(lambda c: c / 100),
    lags,
)
turns = st.builds(
    lambda side, mrad, lag: Landmark("turned", side, angle_rad=mrad / 1000, lag_m=lag),
    sides,
    st.integers(1, int(2 * math.pi * 1000)),
    lags,
)
landmarks = openings | turns
progresses = st.builds(
    lambda a, b, t, r, o: Progress([a, b], t, r, o),
    st.integers(0, 20),
    st.integers(0, 20),
    st.floats(0, 100),
    st.floats(-10, 10),
    st.tuples(st.booleans(), st.booleans()),
)


def _mirror(lm: Landmark) -> Landmark:
    side = "right" if lm.side == "left" else "left"
    return Landmark(lm.kind, side, lm.nth, lm.odometry_m, lm.angle_rad, lag_m=lm.lag_m)


@given(landmarks)
def test_to_dict_and_from_dict_round_trip(lm: Landmark) -> None:
    assert Landmark.from_dict(lm.to_dict(), "x") == lm
    assert lm.describe()  # a line a person reads, never empty


@settings(max_examples=40)
@given(landmarks, progresses)
def test_left_and_right_mirror(lm: Landmark, p: Progress) -> None:
    mirrored = Progress(p.openings[::-1], p.travelled_m, -p.turned_rad, p.onset[::-1])
    assert lm.met(p) == _mirror(lm).met(mirrored)


@settings(max_examples=40)
@given(openings, progresses, st.integers(1, 5))
def test_an_opening_met_as_the_nth_is_met_as_any_earlier_one(lm: Landmark, p: Progress, k: int) -> None:
    earlier = Landmark("opening", lm.side, max(1, lm.nth - k), lm.odometry_m, lag_m=lm.lag_m)
    assert not lm.met(p) or earlier.met(p)


@settings(max_examples=40)
@given(st.lists(st.tuples(st.booleans(), st.booleans(), st.floats(0, 1), st.floats(-1, 1)), max_size=30))
def test_progress_adds_up_the_cues(cues: list[tuple[bool, bool, float, float]]) -> None:
    p = Progress.fresh(0.25)
    for left, right, step, turn in cues:
        p.add(Cues(left, right, step, turn))
    assert p.openings == [sum(c[0] for c in cues), sum(c[1] for c in cues)]
    assert math.isclose(p.travelled_m, sum(c[2] for c in cues), abs_tol=1e-9)
    assert math.isclose(p.turned_rad, 0.25 + sum(c[3] for c in cues), abs_tol=1e-9)
    assert p.onset == ((cues[-1][0], cues[-1][1]) if cues else (False, False))


@pytest.mark.parametrize(
    "bad",
    [
        [],
        {"opening": "left", "turned": "left"},
        {"opening": "up"},
        {"opening": "left", "nth": True},
        {"opening": "left", "nth": 0},
        {"opening": "left", "odometry_m": -1},
        {"turned": "left", "angle_rad": 0},
        {"turned": "left", "angle_rad": 7.0},
        {"turned": "left", "angle_rad": 1.0, "nth": 2},
        {"opening": "left", "lag_m": 0},
        {"opening": "left", "lag_m": 10.5},
        {"turned": "left", "angle_rad": 1.0, "lag_m": True},
        {"turned": "left", "angle_rad": 1.0, "lag_m": "1.5"},
    ],
)
def test_bad_landmarks_are_config_errors(bad: object) -> None:
    with pytest.raises(ConfigError, match=r"^fusion table: step\.done"):
        Landmark.from_dict(bad, "step.done")


@settings(max_examples=40)
@given(
    st.lists(st.tuples(st.booleans(), st.booleans(), st.floats(0, 1), st.floats(-1, 1)), max_size=30),
    st.sampled_from([None, 1.0, 1.5]),
)
def test_progress_counts_the_openings_its_sensor_senses(
    ticks: list[tuple[bool, bool, float, float]], lag: float | None
) -> None:
    """A step sensed with another lag counts that sensor's onsets, the default one's otherwise;
    odometry is the robot's either way."""
    p = Progress.fresh(0.0, lag)
    for default, shorter, step, turn in ticks:
        lagged = tuple((x, Cues(shorter and x == 1.5, False, step, turn)) for x in (1.0, 1.5))
        p.add(Cues(default, False, step, turn, lagged=lagged))
    counted = [d for d, _, _, _ in ticks] if lag is None else [s and lag == 1.5 for _, s, _, _ in ticks]
    assert p.openings == [sum(counted), 0]
    assert math.isclose(p.travelled_m, sum(t[2] for t in ticks), abs_tol=1e-9)
    with pytest.raises(ValueError, match="2.5 m back"):
        Cues(lagged=((1.5, Cues()),)).seen_with(2.5)
