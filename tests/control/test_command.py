from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from lfdfuse.control.command import DriveParams, command_to_heading, heading_to_command, vector_to_command

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
