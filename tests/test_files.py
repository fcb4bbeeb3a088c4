"""Files at the edge: atomic writes round-trip and leave nothing behind; YAML parsing is bounded."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lfdfuse.errors import ConfigError, LfdError, LogError
from lfdfuse.files import (
    MAX_YAML_DEPTH,
    parse_yaml,
    read_text,
    read_yaml,
    umask,
    write_bytes_atomic,
    write_text_atomic,
)
from lfdfuse.log.writer import LogWriter

# the data YAML files hold: scalars, lists and string-keyed mappings
scalars = st.none() | st.booleans() | st.integers(-(10**12), 10**12) | st.text(max_size=12)
documents = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(min_size=1, max_size=8), inner, max_size=4)
    ),
    max_leaves=20,
)


@settings(max_examples=40, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.binary(max_size=2000))
def test_atomic_write_round_trips_and_leaves_no_temp_file(tmp_path: Path, data: bytes) -> None:
    out = tmp_path / "out.bin"
    write_bytes_atomic(out, data)
    assert out.read_bytes() == data
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.bin"]
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask()


class _Interrupted(BaseException):
    """A signal raised as an exception (Ctrl-C, the CLI's SIGTERM) between two lines."""


def _made_then_interrupted(monkeypatch: pytest.MonkeyPatch) -> None:
    """``os.open`` makes its file, then a signal comes before its descriptor is returned."""
    real = os.open

    def open_then_interrupted(path: Any, flags: int, mode: int = 0o777) -> int:
        real(path, flags, mode)
        raise _Interrupted

    monkeypatch.setattr(os, "open", open_then_interrupted)


@pytest.mark.parametrize("write", ["atomic", "mcap"])
def test_a_signal_as_the_temp_file_is_made_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, write: str
) -> None:
    _made_then_interrupted(monkeypatch)
    with pytest.raises(_Interrupted):
        if write == "atomic":
            write_bytes_atomic(tmp_path / "out.bin", b"data")
        else:
            with LogWriter(tmp_path / "out.mcap", metadata={}):
                pass
    monkeypatch.undo()
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_into_a_missing_folder_is_an_lfd_error(tmp_path: Path) -> None:
    with pytest.raises(LfdError, match="does not exist"):
        write_text_atomic(tmp_path / "nope" / "x.yaml", "a: 1\n")


def test_a_failed_write_keeps_the_old_file(tmp_path: Path) -> None:
    out = tmp_path / "table.yaml"
    out.write_text("old\n")
    target_dir = tmp_path / "d"
    target_dir.mkdir()
    with pytest.raises(LfdError):
        write_text_atomic(target_dir, "new\n")  # replacing a folder by a file fails at the rename
    assert out.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "table.yaml"]


@settings(max_examples=40)
@given(documents)
def test_parse_yaml_inverts_safe_dump(data: Any) -> None:
    assert parse_yaml(yaml.safe_dump(data), origin="t") == data


@pytest.mark.parametrize("error", [ConfigError, LogError])
def test_yaml_errors_name_the_origin_and_line_in_the_callers_class(error: type[LfdError]) -> None:
    with pytest.raises(error, match=r"^world\.yaml: malformed YAML at line 2"):
        parse_yaml("a: 1\n- b\n", origin="world.yaml", error=error)


def test_an_anchor_bomb_is_refused_before_it_expands() -> None:
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, 9)]
    with pytest.raises(ConfigError, match="anchor bomb"):
        parse_yaml("\n".join(lines), origin="bomb.yaml")


def test_nesting_is_bounded() -> None:
    assert parse_yaml("[" * (MAX_YAML_DEPTH - 1) + "]" * (MAX_YAML_DEPTH - 1), origin="t") is not None
    with pytest.raises(ConfigError, match="nested deeper"):
        parse_yaml("[" * (MAX_YAML_DEPTH + 1) + "]" * (MAX_YAML_DEPTH + 1), origin="t")


def test_empty_yaml_is_none() -> None:
    assert parse_yaml("", origin="t") is None
    assert parse_yaml("# only a comment\n", origin="t") is None


def test_read_text_refuses_what_is_not_a_utf8_regular_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read task file"):
        read_text(tmp_path / "missing.yaml", what="task file")
    with pytest.raises(ConfigError, match="not a regular file"):
        read_text(tmp_path, what="task file")
    bad = tmp_path / "latin.yaml"
    bad.write_bytes(b"name: caf\xe9\n")
    with pytest.raises(ConfigError, match="not UTF-8 at byte 9"):
        read_text(bad, what="task file")
    good = tmp_path / "good.yaml"
    write_text_atomic(good, "legs: [a, b]\n")
    assert read_yaml(good, what="task file") == {"legs": ["a", "b"]}
    assert os.path.getsize(good) == len("legs: [a, b]\n")
