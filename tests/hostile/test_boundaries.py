"""The readers' boundary laws, one class at a time, below the CLI: the YAML loader, the
shared numeric validator, the MCAP reader's lengths and times, stamps, metadata, and tasks."""

from __future__ import annotations

import io
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.errors import ConfigError, LfdError, LogError, WorldError
from lfdfuse.files import MAX_CONFIG_BYTES, parse_yaml
from lfdfuse.log import reader
from lfdfuse.log.stamps import MAX_T_NS, MIN_T_NS, from_stamp, stamp
from lfdfuse.sources.tasks import parse_task
from lfdfuse.validate import integer, number
from tests.hostile import boundaries
from tests.hostile.base import craft, plain_log

# --- the YAML loader: keys are names, integers fit a number ---------------------------------


@pytest.mark.parametrize(
    "text",
    [
        "1: x\n",
        "a: 1\n2: x\n",
        "~: x\n",
        "true: x\n",
        "1.5: x\n",
        "? [a, b]\n: x\n",
        "? {a: 1}\n: x\n",
        "walls:\n  - {name: a, 3: b}\n",
        "a:\n  b:\n    - c: {7: 1}\n",
        "2001-01-01: x\n",
    ],
)
def test_a_mapping_key_that_is_not_a_string_is_refused_naming_its_line(text: str) -> None:
    with pytest.raises(ConfigError, match=r"mapping key .* at line \d+ must be a name") as info:
        parse_yaml(text, origin="f.yaml")
    line = int(str(info.value).split(" at line ")[1].split()[0])
    assert 1 <= line <= text.count("\n")


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ('"1": x\n', {"1": "x"}),
        ("!!str 1: x\n", {"1": "x"}),
        ("a: &a {b: 1}\nc: {<<: *a, d: 2}\n", {"a": {"b": 1}, "c": {"b": 1, "d": 2}}),
        ("a: [1, 2.5, -3]\n", {"a": [1, 2.5, -3]}),
    ],
)
def test_string_keys_and_merges_still_load(text: str, expected: Any) -> None:
    assert parse_yaml(text, origin="f.yaml") == expected


@pytest.mark.parametrize("digits", [401, 4300, 5000, 100_000])
def test_an_integer_literal_too_long_for_a_number_is_refused_before_it_is_parsed(digits: int) -> None:
    with pytest.raises(WorldError, match=f"an integer of {digits} digits at line 2"):
        parse_yaml("a: 1\nb: " + "9" * digits + "\n", origin="w.yaml", error=WorldError)


@pytest.mark.parametrize("text", ["a: 2001-13-45\n", "a: 2001-02-30\n"])
def test_a_scalar_its_constructor_refuses_is_a_one_line_error(text: str) -> None:
    with pytest.raises(ConfigError, match="malformed YAML value"):
        parse_yaml(text, origin="f.yaml")


# --- the numeric validator -----------------------------------------------------------------


@settings(max_examples=80, deadline=None)
@given(
    st.one_of(
        st.integers(min_value=-(10**400), max_value=10**400),
        st.floats(allow_nan=True, allow_infinity=True),
        st.booleans(),
        st.text(max_size=5),
        st.none(),
    )
)
def test_number_returns_the_float_or_raises_the_callers_error(value: Any) -> None:
    try:
        x = number(value, "f", error=WorldError, lo=-1e300, hi=1e300)
    except WorldError as exc:
        assert str(exc).startswith("f must be a number in") and len(str(exc)) < 200
        return
    assert not isinstance(value, (bool, str)) and value is not None
    assert x == float(value) and math.isfinite(x) and -1e300 <= x <= 1e300


@settings(max_examples=100, deadline=None)
@given(st.integers(min_value=-(10**400), max_value=10**400))
def test_integer_keeps_what_is_in_range(value: int) -> None:
    try:
        assert integer(value, "n", lo=0, hi=2**63 - 1) == value
    except ConfigError:
        assert not 0 <= value <= 2**63 - 1


# --- the MCAP reader: reads bounded by the file, times within int64 ---------------------------


@settings(max_examples=50, deadline=None)
@given(size=st.integers(0, 4096), at=st.integers(0, 5000), ask=st.integers(0, 2**62))
def test_a_bounded_read_never_asks_for_more_than_is_left(
    tmp_path_factory: Any, size: int, at: int, ask: int
) -> None:
    path = tmp_path_factory.mktemp("b") / "f.bin"
    path.write_bytes(bytes(range(256)) * (size // 256) + bytes(size % 256))
    with reader._Bounded(io.FileIO(path, "rb")) as f:
        f.seek(at)
        got = f.read(ask)
    assert got == path.read_bytes()[at : at + ask]


@pytest.mark.parametrize("name", ["chunk-data-huge-cut", "chunk-uncompressed-huge", "unsized-chunk-huge"])
def test_a_chunk_claiming_more_than_the_file_is_a_log_error(tmp_path: Path, name: str) -> None:
    from tests.hostile.base import build_base

    content, _codes = boundaries.MCAPS[name]
    base = build_base(tmp_path)
    path = tmp_path / "d.mcap"
    path.write_bytes(content(base))
    with pytest.raises(LogError, match="not a readable MCAP file"):
        reader.read_run(path)


def test_an_unsized_chunk_of_honest_size_reads(tmp_path: Path) -> None:
    path = tmp_path / "d.mcap"
    path.write_bytes(boundaries._unsized_chunk(-1)(None))  # type: ignore[arg-type]
    assert len(reader.read_run(path)) == 30


@pytest.mark.parametrize("t_ns", [2**63, 2**64 - 1])
def test_a_log_time_past_int64_is_a_log_error(tmp_path: Path, t_ns: int) -> None:
    path = tmp_path / "d.mcap"
    path.write_bytes(boundaries._late(t_ns, header=0)(None))  # type: ignore[arg-type]
    with pytest.raises(LogError, match="past the int64"):
        reader.read_run(path)
    with pytest.raises(LogError, match="past the int64"):
        list(reader.iter_raw(path))


@settings(max_examples=100, deadline=None)
@given(st.integers(min_value=MIN_T_NS, max_value=MAX_T_NS))
def test_stamps_round_trip_over_int64(t_ns: int) -> None:
    assert from_stamp(stamp(t_ns)) == t_ns


@pytest.mark.parametrize(
    "d",
    [
        {"sec": 2**64, "nsec": 0},
        {"sec": "1", "nsec": 0},
        {"sec": 1.5, "nsec": 0},
        {"sec": math.inf, "nsec": 0},
    ],
    ids=repr,
)
def test_a_stamp_that_is_not_an_int64_time_is_a_value_error(d: dict[str, Any]) -> None:
    with pytest.raises(ValueError, match="stamp"):
        from_stamp(d)


@pytest.mark.parametrize(
    ("text", "ok"),
    [("8.0", True), ("inf", True), ("far", False), ("nan", False), ("0", False), ("-1", False)],
)
def test_a_max_range_in_metadata_is_a_positive_number_or_an_error(text: str, ok: bool) -> None:
    if ok:
        assert reader.meta_float({"laser_max_range_m": text}, "laser_max_range_m", 1.0) == float(text)
    else:
        with pytest.raises(LogError, match="laser_max_range_m must be a positive number"):
            reader.meta_float({"laser_max_range_m": text}, "laser_max_range_m", 1.0, path="d.mcap")
    assert reader.meta_float({}, "laser_max_range_m", 1.0) == 1.0


def test_a_log_with_a_max_range_that_is_not_a_number_does_not_load(tmp_path: Path) -> None:
    path = tmp_path / "d.mcap"
    path.write_bytes(craft(plain_log(), metadata={"lfdfuse": {"laser_max_range_m": "far"}}))
    with pytest.raises(LogError, match="'far'"):
        reader.read_run(path)


# --- tasks: bounded by the file, not by a count ------------------------------------------------


def test_a_task_of_ten_thousand_legs_is_valid() -> None:
    text = "task:\n" + "  - {target: red, style: keep-left}\n" * 10_000
    legs = parse_task(parse_yaml(text, origin="t.yaml"), origin="t.yaml")
    assert len(legs) == 10_000 and {leg.style for leg in legs} == {"keep-left"}


def test_a_task_bigger_than_a_config_file_may_be_is_refused() -> None:
    leg = "  - {target: red, style: keep-left}\n"
    text = "task:\n" + leg * (MAX_CONFIG_BYTES // len(leg) + 1)
    with pytest.raises(LfdError, match="larger than"):
        parse_yaml(text, origin="t.yaml")
