"""The behaviour network runtime: active step, goals, and the fallbacks for unseen BACs."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.behaviors.primitives import BehaviorOutputs
from lfdfuse.network.landmark_goals import Cues
from lfdfuse.network.runtime import DRIVE_ON_RAD, SETTLE_M, SETTLE_RAD, NetworkRuntime, step_name_of
from lfdfuse.network.table import FusionTable, parse_table

NAMES = ("avoid", "attract_red", "wander", "attract_blue")


def table(**over: Any) -> FusionTable:
    data: dict[str, Any] = {
        "format": "lfdfuse/fusion-table@1",
        "behaviors": list(NAMES),
        "default_weights": {"avoid": 0.5, "wander": 0.5},
        "network": {
            "name": "t",
            "steps": [
                {
                    "name": "reach-red",
                    "goal": {"target": "red"},
                    "default_weights": {"wander": 1.0},
                    "fusion": [{"bac": 0b0111, "weights": {"avoid": 0.2, "attract_red": 0.7, "wander": 0.1}}],
                },
                {
                    "name": "reach-blue",
                    "goal": {"target": "blue"},
                    "fusion": [{"bac": 0b1101, "weights": {"avoid": 0.3, "attract_blue": 0.7}}],
                },
            ],
        },
    }
    data.update(over)
    return parse_table(data)


def outputs(vectors: np.ndarray, applicable: list[bool]) -> BehaviorOutputs:
    return BehaviorOutputs(NAMES, vectors[None], np.array([applicable]), np.zeros((1, len(NAMES)), bool))


VEC = np.array([[1.0, 0.0], [0.0, 1.0], [0.6, -0.8], [-1.0, 0.0]])


def test_a_seen_bac_fuses_its_row() -> None:
    dec = NetworkRuntime(table()).decide(outputs(VEC, [True, True, True, False]), set())
    assert dec.bac == 0b0111 and not dec.unseen
    assert np.allclose(dec.fused, 0.2 * VEC[0] + 0.7 * VEC[1] + 0.1 * VEC[2])


def test_an_unseen_bac_uses_the_steps_default_then_the_tables() -> None:
    rt = NetworkRuntime(table())
    dec = rt.decide(outputs(VEC, [True, False, True, False]), set())  # bac 0b0101: never seen in step 0
    assert dec.unseen and dec.weights == {"wander": 1.0} and np.allclose(dec.fused, VEC[2])
    rt.decide(outputs(VEC, [True, True, True, False]), {"red"})  # red reached: step 1 is active
    dec = rt.decide(outputs(VEC, [True, False, True, False]), set())
    assert dec.unseen and dec.weights == {"avoid": 0.5, "wander": 0.5}  # step 1 has no own default
    assert step_name_of(dec.path, rt.table) == "reach-blue"


def test_a_row_whose_fusion_cancels_falls_back_to_the_default() -> None:
    vec = VEC.copy()
    vec[1] = -(0.2 * vec[0] + 0.1 * vec[2]) / 0.7  # the row's weighted sum is exactly zero
    dec = NetworkRuntime(table()).decide(outputs(vec, [True, True, True, False]), set())
    assert np.allclose(dec.fused, vec[2])  # the step's default: wander


def test_goals_are_reached_in_order_and_stay_achieved() -> None:
    rt = NetworkRuntime(table())
    o = outputs(VEC, [True, True, True, True])
    assert rt.decide(o, {"blue"}).achieved_now == ()  # blue is not the active goal yet
    assert rt.decide(o, {"red"}).achieved_now == ("red",)
    assert rt.decide(o, set()).step is not None and not rt.complete  # red stays achieved
    dec = rt.decide(o, {"blue"})
    assert dec.achieved_now == ("blue",) and dec.step is None and rt.complete


def test_a_network_without_goals_never_completes() -> None:
    t = table(network={"name": "free", "steps": [{"name": "free", "goal": None, "fusion": []}]})
    rt = NetworkRuntime(t)
    for _ in range(3):
        dec = rt.decide(outputs(VEC, [True, False, True, False]), {"red", "blue"})
        assert dec.step is not None and dec.unseen
    assert not rt.complete


@settings(max_examples=60, deadline=None)
@given(st.lists(st.booleans(), min_size=4, max_size=4), st.integers(0, 2**31 - 1))
def test_the_fused_vector_is_the_weighted_sum_of_applicable_outputs(app: list[bool], seed: int) -> None:
    rng = np.random.default_rng(seed)
    vec = rng.uniform(-1, 1, (4, 2))
    dec = NetworkRuntime(table()).decide(outputs(vec, app), set())
    expect = sum(w * vec[NAMES.index(n)] for n, w in dec.weights.items())
    if float(np.hypot(*expect)) > 1e-9:
        assert np.allclose(dec.fused, expect)


def _drive_on(ahead: str | None, lag: float | None = None) -> FusionTable:
    """One goal step whose first sub-step drives on to the 1st opening on the left, of shape
    ``ahead`` (sensed with ``lag``), with ``wander`` alone."""
    landmark: dict[str, Any] = {"opening": "left", "nth": 1, "odometry_m": 50.0}
    if ahead is not None:
        landmark["ahead"] = ahead
    if lag is not None:
        landmark["lag_m"] = lag
    step = {
        "name": "reach-red",
        "goal": {"target": "red"},
        "network": {
            "name": "reach-red",
            "steps": [
                {
                    "name": "to-left-opening-1",
                    "landmark": landmark,
                    "fusion": [{"bac": 0b0100, "weights": {"wander": 1.0}}],
                },
                {"name": "reach-red", "goal": {"target": "red"}, "fusion": []},
            ],
        },
    }
    return table(network={"name": "t", "steps": [step]})


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-3.1, 3.1),
    st.floats(-1.0, 1.0),
    st.booleans(),
    st.sampled_from(["open", "closed", None]),
    st.sampled_from([None, 1.5]),
)
def test_a_step_driving_on_to_a_side_opening_keeps_near_the_held_heading(
    pull: float, held: float, ahead_open: bool, shape: str | None, lag: float | None
) -> None:
    """Driving on to a side opening (the way ahead goes on there), the fused heading stays within
    DRIVE_ON_RAD of the held heading while the way ahead is open, its length kept; otherwise (a
    corner ahead, or an opening where the way ends) the row's fusion is untouched. The heading and
    the way ahead are the default sensor's, whatever sensor the landmark is met with."""
    vec = np.zeros((4, 2))
    vec[2] = [2.0 * math.cos(pull), 2.0 * math.sin(pull)]
    other = Cues(held_turn_rad=-held, ahead_open=not ahead_open)
    cues = Cues(held_turn_rad=held, ahead_open=ahead_open, lagged=((1.5, other),))
    t = _drive_on(shape, lag)
    dec = NetworkRuntime(t).decide(outputs(vec, [False, False, True, False]), set(), cues)
    assert step_name_of(dec.path, t) == "reach-red/to-left-opening-1"
    assert math.isclose(float(np.hypot(*dec.fused)), 2.0)
    off = math.atan2(dec.fused[1], dec.fused[0]) + held  # from the held heading (at -held)
    off = math.atan2(math.sin(off), math.cos(off))
    raw = math.atan2(math.sin(pull + held), math.cos(pull + held))
    if ahead_open and shape == "open":
        assert abs(off) <= DRIVE_ON_RAD + 1e-9
        assert math.isclose(off, max(-DRIVE_ON_RAD, min(DRIVE_ON_RAD, raw)), abs_tol=1e-9)
    else:
        assert np.allclose(dec.fused, vec[2])


def _turn(side: str, angle_rad: float) -> FusionTable:
    """One goal step whose sub-steps turn ``angle_rad`` to ``side`` with ``wander`` alone, then
    reach red with ``wander`` alone."""
    sub = [
        {
            "name": f"turn-{side}",
            "landmark": {"turned": side, "angle_rad": angle_rad},
            "fusion": [{"bac": 0b0100, "weights": {"wander": 1.0}}],
        },
        {
            "name": "reach-red",
            "goal": {"target": "red"},
            "fusion": [{"bac": 0b0100, "weights": {"wander": 1.0}}],
        },
    ]
    step = {"name": "reach-red", "goal": {"target": "red"}, "network": {"name": "reach-red", "steps": sub}}
    return table(network={"name": "t", "steps": [step]})


def _pull(a: float) -> BehaviorOutputs:
    """Only ``wander`` applies, pulling at bearing ``a`` with length 2."""
    vec = np.zeros((4, 2))
    vec[2] = [2.0 * math.cos(a), 2.0 * math.sin(a)]
    return outputs(vec, [False, False, True, False])


@settings(max_examples=60, deadline=None)
@given(st.floats(-3.1, 3.1), st.sampled_from(["left", "right"]))
def test_a_turn_step_never_steers_to_the_other_side(pull: float, side: str) -> None:
    """A turn to a side is met only by turning that way: a pull to the other side (the turn's
    rows where the robot is not where the teacher turned) drives straight on, its length kept."""
    t = _turn(side, 1.0)
    dec = NetworkRuntime(t).decide(_pull(pull), set(), Cues())
    assert step_name_of(dec.path, t) == f"reach-red/turn-{side}"
    sign = 1.0 if side == "left" else -1.0
    if sign * pull >= 0.0:
        assert np.allclose(dec.fused, [2.0 * math.cos(pull), 2.0 * math.sin(pull)])
    else:
        assert np.allclose(dec.fused, [2.0, 0.0])


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.3, 2.5),
    st.sampled_from(["left", "right"]),
    st.lists(st.floats(-3.1, 3.1), min_size=1, max_size=30),
    st.floats(0.05, 0.4),
    st.booleans(),
)
def test_the_step_after_a_turn_keeps_to_the_heading_the_turn_ended_on(
    angle: float, side: str, pulls: list[float], step_m: float, front_open: bool
) -> None:
    """Once the turn is met, the next step keeps the fused heading within SETTLE_RAD of the
    heading the turn ended on for SETTLE_M of travel, its length kept — only where the way ahead
    was open as the turn ended; after that, and otherwise, the row's fusion is untouched."""
    t = _turn(side, angle)
    rt = NetworkRuntime(t)
    sign = 1.0 if side == "left" else -1.0
    rt.decide(_pull(sign * 0.5), set(), Cues())
    dec = rt.decide(_pull(0.0), set(), Cues(turn_rad=sign * (angle + 0.01), front_open=front_open))
    assert step_name_of(dec.path, t) == "reach-red/reach-red"  # the turn is met: the goal's step runs
    heading = travelled = 0.0  # since the turn ended
    for pull in pulls:
        turn = 0.3 * math.sin(7.0 * pull)  # the robot turns some way each tick
        heading += turn
        travelled += step_m
        dec = rt.decide(_pull(pull), set(), Cues(step_m=step_m, turn_rad=turn))
        assert math.isclose(float(np.hypot(*dec.fused)), 2.0)
        raw = np.array([2.0 * math.cos(pull), 2.0 * math.sin(pull)])
        if front_open and travelled < SETTLE_M:
            off = math.atan2(dec.fused[1], dec.fused[0]) + heading  # from the turn's end heading
            off = math.atan2(math.sin(off), math.cos(off))
            want = math.atan2(math.sin(pull + heading), math.cos(pull + heading))
            assert math.isclose(off, max(-SETTLE_RAD, min(SETTLE_RAD, want)), abs_tol=1e-9)
        else:
            assert np.allclose(dec.fused, raw)


def _lagged(lag: float | None) -> FusionTable:
    """Drive on to the 1st opening on the left, turn 1 rad left, reach red (``wander`` alone);
    both landmarks sensed with ``lag`` (None: the default sensor)."""
    sensed = {} if lag is None else {"lag_m": lag}
    rows = [{"bac": 0b0100, "weights": {"wander": 1.0}}]
    sub = [
        {"name": "to-left-opening-1", "landmark": {"opening": "left", "nth": 1, **sensed}, "fusion": rows},
        {"name": "turn-left", "landmark": {"turned": "left", "angle_rad": 1.0, **sensed}, "fusion": rows},
        {"name": "reach-red", "goal": {"target": "red"}, "fusion": rows},
    ]
    step = {"name": "reach-red", "goal": {"target": "red"}, "network": {"name": "reach-red", "steps": sub}}
    return table(network={"name": "t", "steps": [step]})


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(st.booleans(), st.booleans(), st.floats(-0.5, 0.5), st.floats(-0.5, 0.5)),
        min_size=1,
        max_size=25,
    ),
    st.sampled_from([None, 1.5]),
)
def test_a_landmark_sensed_with_another_lag_is_met_by_that_sensor_alone(
    ticks: list[tuple[bool, bool, float, float]], lag: float | None
) -> None:
    """The drive-on step ends at the first onset of the sensor its landmark names (the default
    one's onsets, or the other's, do not end it), and the turn after it counts from the heading
    that sensor's sectors were held at then."""
    t = _lagged(lag)
    rt = NetworkRuntime(t)
    mine = [s if lag else d for d, s, _, _ in ticks]
    for k, (default, shorter, held_d, held_s) in enumerate(ticks):
        other = Cues(onset_left=shorter, held_turn_rad=held_s)
        dec = rt.decide(
            _pull(0.0), set(), Cues(onset_left=default, held_turn_rad=held_d, lagged=((1.5, other),))
        )
        met = any(mine[: k + 1])
        assert step_name_of(dec.path, t) == ("reach-red/turn-left" if met else "reach-red/to-left-opening-1")
        if met and not any(mine[:k]):  # met at this tick: the turn counts from the held heading now
            assert rt.progress.turned_rad == (held_s if lag else held_d)
            assert rt.progress.lag_m == lag


@settings(max_examples=40, deadline=None)
@given(st.lists(st.lists(st.booleans(), min_size=4, max_size=4), min_size=1, max_size=30))
def test_each_ticks_bac_is_its_outputs_bac_pattern_after_pattern(apps: list[list[bool]]) -> None:
    """The BAC a decision reads off its applicability (once per pattern, then looked up) is
    ``BehaviorOutputs.bac``, however the patterns repeat."""
    rt = NetworkRuntime(table())
    for app in apps:
        out = outputs(VEC, app)
        assert rt.decide(out, set()).bac == int(out.bac[0]) == sum(1 << j for j, a in enumerate(app) if a)
