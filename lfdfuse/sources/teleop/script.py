"""Scripted teleop input: timed keys and Twists from a YAML or CSV file.

A script stands in for the person: the session runs the same loop, with a simulated clock so
it goes faster than real time (tests, reproducible demos). Each entry takes effect in the
first control period at or after its time; a command holds until the next entry.

YAML: a list (or ``{inputs: [...]}``) of entries with ``t`` (seconds) and one of
``key`` (a key name of :mod:`~lfdfuse.sources.teleop.keys`: ``i``, ``up``, ``space``,
``esc``, …), ``twist: [v, ω]`` (m/s, rad/s, as a client would publish it), ``end: true``, or
(when a network drives, ``teleop --table``) ``handback: true``, which gives control back to it::

    - {t: 0.0, key: i}
    - {t: 2.5, twist: [0.3, 0.4]}
    - {t: 6.0, handback: true}
    - {t: 9.0, key: esc}

CSV: a header with ``t`` and ``key`` and/or ``v``, ``w`` columns; one entry per row, a
row with a key uses the key, otherwise the Twist::

    t,key,v,w
    0.0,i,,
    2.5,,0.3,0.4
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lfdfuse.errors import ConfigError
from lfdfuse.files import parse_yaml as read_yaml_text
from lfdfuse.sources.teleop.inputs import Input
from lfdfuse.sources.teleop.keys import is_key_name

SOURCE = "script"
TWIST_SCHEMA = "geometry_msgs/msg/Twist"
_MAX_ENTRIES = 1_000_000


@dataclass(frozen=True)
class ScriptEntry:
    """One input at time ``t_ns`` (integer nanoseconds from the start)."""

    t_ns: int
    input: Input


def twist_payload(v_mps: float, omega_rps: float) -> str:
    """The JSON a Foxglove Teleop panel publishes for a command (all six fields)."""
    return json.dumps(
        {"linear": {"x": v_mps, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": omega_rps}}
    )


def key_entry(t_s: float, key: str) -> ScriptEntry:
    return ScriptEntry(_t_ns(t_s, "t"), Input("key", key, SOURCE))


def twist_entry(t_s: float, v_mps: float, omega_rps: float) -> ScriptEntry:
    return ScriptEntry(
        _t_ns(t_s, "t"), Input("message", twist_payload(v_mps, omega_rps), SOURCE, TWIST_SCHEMA)
    )


def end_entry(t_s: float) -> ScriptEntry:
    return ScriptEntry(_t_ns(t_s, "t"), Input("end", "script ended", SOURCE))


def handback_entry(t_s: float) -> ScriptEntry:
    return ScriptEntry(_t_ns(t_s, "t"), Input("handback", "script", SOURCE))


class ScriptInput:
    """An :class:`~lfdfuse.sources.teleop.inputs.InputSource` replaying entries by time.

    The run ends at an ``end`` entry, or, without one, in the period of the last entry — unless
    ``end_with_last`` is False (a network drives on after the script's last correction).
    """

    def __init__(self, entries: Sequence[ScriptEntry], *, end_with_last: bool = True) -> None:
        ordered = sorted(entries, key=lambda e: e.t_ns)  # stable: same-time entries keep order
        if end_with_last and ordered and not any(e.input.kind == "end" for e in ordered):
            # a script without an end ends with its last entry (which still takes effect)
            ordered.append(ScriptEntry(ordered[-1].t_ns, Input("end", "script ended", SOURCE)))
        self.entries = ordered
        self._next = 0

    @property
    def finished(self) -> bool:
        return self._next >= len(self.entries)

    def poll(self, t_s: float) -> list[Input]:
        now_ns = round(t_s * 1e9)
        out: list[Input] = []
        while self._next < len(self.entries) and self.entries[self._next].t_ns <= now_ns:
            out.append(self.entries[self._next].input)
            self._next += 1
        return out


def load_script(path: str | Path) -> list[ScriptEntry]:
    """Read a YAML or CSV script; a clear :class:`ConfigError` naming the entry on bad input."""
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise ConfigError(f"cannot read teleop script {p}: {exc.strerror}") from None
    if p.suffix.lower() == ".csv":
        return parse_csv(text, name=str(p))
    # the one capped YAML reader: one line naming the file and line, like every other YAML input
    return parse_yaml(read_yaml_text(text, origin=f"teleop script {p}"), name=str(p))


def parse_yaml(data: Any, *, name: str = "script") -> list[ScriptEntry]:
    if isinstance(data, dict) and set(data) == {"inputs"}:
        data = data["inputs"]
    if not isinstance(data, list) or not data:
        raise ConfigError(
            f"{name}: a teleop script is a non-empty list of {{t: …, key|twist|end|handback: …}}"
        )
    if len(data) > _MAX_ENTRIES:
        raise ConfigError(f"{name}: more than {_MAX_ENTRIES} entries")
    out: list[ScriptEntry] = []
    for i, item in enumerate(data):
        where = f"{name} entry {i + 1}"
        if not isinstance(item, dict) or "t" not in item:
            raise ConfigError(f"{where}: needs a time t")
        unknown = set(item) - {"t", "key", "twist", "end", "handback"}
        if unknown:
            raise ConfigError(f"{where}: unknown key {sorted(unknown)[0]!r}")
        what = [k for k in ("key", "twist", "end", "handback") if k in item]
        if len(what) != 1:
            raise ConfigError(f"{where}: give exactly one of key, twist, end, handback")
        t = _seconds(item["t"], f"{where}: t")
        if what[0] == "key":
            if not isinstance(item["key"], str) or not is_key_name(item["key"]):
                raise ConfigError(
                    f"{where}: key {str(item['key'])[:20]!r} is not a key name (a character, or up, down,"
                    " left, right, space, esc, enter)"
                )
            out.append(key_entry(t, item["key"]))
        elif what[0] == "twist":
            tw = item["twist"]
            if not isinstance(tw, list) or len(tw) != 2:
                raise ConfigError(f"{where}: twist must be [v, w] (m/s, rad/s)")
            out.append(twist_entry(t, _number(tw[0], f"{where}: v"), _number(tw[1], f"{where}: w")))
        elif item[what[0]] is not True:
            raise ConfigError(f"{where}: {what[0]} must be true")
        elif what[0] == "end":
            out.append(end_entry(t))
        else:
            out.append(handback_entry(t))
    return out


def parse_csv(text: str, *, name: str = "script") -> list[ScriptEntry]:
    reader = csv.DictReader(io.StringIO(text))
    cols = set(reader.fieldnames or [])
    if "t" not in cols or not ({"key"} <= cols or {"v", "w"} <= cols):
        raise ConfigError(f"{name}: a CSV teleop script needs a header with t and key, or t, v and w")
    out: list[ScriptEntry] = []
    for i, row in enumerate(reader):
        where = f"{name} line {i + 2}"
        if i >= _MAX_ENTRIES:
            raise ConfigError(f"{name}: more than {_MAX_ENTRIES} entries")
        t = _seconds(row.get("t"), f"{where}: t")
        key = (row.get("key") or "").strip()
        if key:
            if not is_key_name(key):
                raise ConfigError(
                    f"{where}: key {key[:20]!r} is not a key name (a character, or up, space, esc …)"
                )
            out.append(key_entry(t, key))
        else:
            out.append(
                twist_entry(t, _number(row.get("v"), f"{where}: v"), _number(row.get("w"), f"{where}: w"))
            )
    if not out:
        raise ConfigError(f"{name}: the teleop script has no entries")
    return out


def write_csv(entries: Sequence[ScriptEntry]) -> str:
    """The CSV form of twist and key entries (the inverse of :func:`parse_csv`)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["t", "key", "v", "w"])
    for e in entries:
        t = f"{e.t_ns / 1e9:.3f}"
        if e.input.kind == "key":
            w.writerow([t, e.input.text, "", ""])
        elif e.input.kind == "message":
            msg = json.loads(e.input.text)
            w.writerow([t, "", repr(msg["linear"]["x"]), repr(msg["angular"]["z"])])
    return buf.getvalue()


def _number(value: Any, what: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{what} must be a number, got {value!r}") from None
    if isinstance(value, bool) or not math.isfinite(x):
        raise ConfigError(f"{what} must be a finite number, got {value!r}")
    return x


def _seconds(value: Any, what: str) -> float:
    t = _number(value, what)
    if t < 0 or t > 1e7:
        raise ConfigError(f"{what} must be between 0 and 1e7 seconds, got {value!r}")
    return t


def _t_ns(t_s: float, what: str) -> int:
    if not (math.isfinite(t_s) and t_s >= 0):
        raise ConfigError(f"{what} must be a time of at least 0 s, got {t_s!r}")
    return round(t_s * 1e9)
