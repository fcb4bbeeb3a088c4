from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from lfdfuse.control.command import (
    DriveParams,
    command_to_heading,
    heading_command,
    heading_to_command,
    vector_to_command,
)

P = DriveParams()


@given(st.floats(-np.pi + 1e-6, np.pi - 1e-6))
def test_heading_round_trip_within_the_forward_half(theta: float) -> None:
    v, w = heading_to_command(np.array([theta]), P)
    back, ok = command_to_heading(v, w, P)
    if abs(theta) <= np.pi / 2:
        assert abs(back[0] - theta) < 1e-9
    else:  # beyond 90° the robot turns on the spot: the heading is ±90°
        assert abs(back[0] - np.sign(theta) * np.pi / 2) < 1e-9
    assert ok[0]
    assert 0.0 <= v[0] <= P.v_max_mps and abs(w[0]) <= P.omega_max_rps


def test_stationary_commands_carry_no_heading() -> None:
    _, ok = command_to_heading(np.array([0.0, 0.2, 0.0]), np.array([0.0, 0.0, 0.5]), P)
    assert ok.tolist() == [False, True, True]


def test_zero_vector_stops() -> None:
    v, w = vector_to_command(np.array([0.0]), np.array([0.0]), P)
    assert v[0] == 0.0 and w[0] == 0.0


@given(
    st.one_of(
        st.floats(-10.0, 10.0),
        st.sampled_from([0.0, -0.0, math.pi, -math.pi, math.pi / 2, -math.pi / 2, 1e-300, math.nan, 1.0472]),
    )
)
def test_one_heading_commands_as_the_arrays_do(heading: float) -> None:
    """``heading_command`` of a float: ``heading_to_command`` of it as an array, bit for bit."""
    p = DriveParams()
    v, w = heading_to_command(np.array(heading), p)
    got = heading_command(heading, p)
    assert np.array([got[0], got[1]]).tobytes() == np.array([float(v), float(w)]).tobytes()
