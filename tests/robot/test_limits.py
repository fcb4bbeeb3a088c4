"""The robot's limits as a log's or a table's provenance states them: one reading for segment and drive."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.robot.limits import stated_limits


def test_stated_limits_read_numbers_and_their_text() -> None:
    assert stated_limits({"v_max_mps": "0.3", "omega_max_rps": 1.25}) == (0.3, 1.25)
    assert stated_limits({"v_max_mps": 2, "omega_max_rps": "1e-1"}) == (2.0, 0.1)


def test_a_limit_not_stated_or_not_usable_is_none() -> None:
    assert stated_limits({}) == (None, None)
    for bad in ("fast", "nan", "-0.3", "0", math.inf, None, [0.3]):
        assert stated_limits({"v_max_mps": bad, "omega_max_rps": "0.5"}) == (None, 0.5), bad


TEXTS = st.sampled_from(["0.4", "-1", "0", "1e300", "1e-320", "nan", "-inf", " 2 ", "0x1p-2", "fast", ""])


@settings(max_examples=200, deadline=None)
@given(
    st.dictionaries(
        st.sampled_from(["v_max_mps", "omega_max_rps", "other"]),
        st.one_of(TEXTS, st.floats(), st.integers(), st.none(), st.booleans()),
    )
)
def test_a_stated_limit_is_positive_and_finite(provenance: dict[str, object]) -> None:
    for value in stated_limits(provenance):
        assert value is None or (math.isfinite(value) and value > 0)
