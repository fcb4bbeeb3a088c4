"""Stamps and planar rotations: the wire form round-trips exactly, for any time and heading."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from lfdfuse.log.stamps import IDENTITY_POSE, from_stamp, quat_z, stamp, yaw_of

# int64 nanoseconds, as MCAP log times are (epoch stamps of real logs included)
times = st.integers(min_value=0, max_value=2**63 - 1)
headings = st.floats(min_value=-50.0, max_value=50.0, allow_nan=False)


@given(times)
def test_stamp_round_trips_and_is_normalised(t_ns: int) -> None:
    s = stamp(t_ns)
    assert 0 <= s["nsec"] < 1_000_000_000
    assert s["sec"] >= 0
    assert from_stamp(s) == t_ns


@given(times, times)
def test_stamps_keep_time_order(a: int, b: int) -> None:
    """Comparing (sec, nsec) pairs orders like comparing the nanoseconds."""
    sa, sb = stamp(a), stamp(b)
    assert ((sa["sec"], sa["nsec"]) < (sb["sec"], sb["nsec"])) == (a < b)


@given(headings)
def test_quaternion_is_unit_and_yaw_inverts_it(theta: float) -> None:
    q = quat_z(theta)
    assert math.isclose(sum(v * v for v in q.values()), 1.0, rel_tol=1e-12)
    wrapped = math.atan2(math.sin(theta), math.cos(theta))
    got = yaw_of(q)
    assert -math.pi <= got <= math.pi
    # equal as angles (±π are the same heading)
    assert abs(math.atan2(math.sin(got - wrapped), math.cos(got - wrapped))) < 1e-9


def test_identity_pose_has_zero_yaw() -> None:
    assert yaw_of(IDENTITY_POSE["orientation"]) == 0.0
    assert IDENTITY_POSE["position"] == {"x": 0.0, "y": 0.0, "z": 0.0}
