"""The readers' boundary classes as hostile cases: numbers past a float, mapping keys that are
not names, lengths that claim more than the file holds, times past int64, metadata that is not a
number, weighted targets the world lacks, and a long task that is valid.

Each class is a family of inputs built from the valid base files by one change, so a case that
passes for the wrong reason (an earlier check) is visible as its siblings' error lines differ.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterator

import zstandard
from mcap.data_stream import RecordBuilder
from mcap.records import Channel, Chunk, DataEnd, Footer, Header, Message, Schema

from tests.hostile.base import TABLE_YAML, TASK_YAML, WORLD_YAML, Base, craft, plain_log, scan
from tests.hostile.runner import Case, Content

OK = frozenset({0})
ERROR = frozenset({1})
OK_OR_ERROR = frozenset({0, 1})

BIG_330 = str(10**330)  # past a float (1.8e308), short enough for the YAML loader
BIG_400 = str(10**400)  # an integer literal longer than the loader reads
BIG_5000 = "9" * 5000  # past Python's own 4300-digit limit on int("...")


def _replace(text: str, old: str, new: str) -> str:
    assert old in text, old  # the base files changed: the case would test nothing
    return text.replace(old, new, 1)


# --- numbers past a float --------------------------------------------------------------------

NUMBERS: dict[str, tuple[str, str, str]] = {
    # name: (file, text in it, replacement)
    "world-wall-330": ("world", "[12, 0]", f"[{BIG_330}, 0]"),
    "world-wall-400": ("world", "[12, 0]", f"[{BIG_400}, 0]"),
    "world-wall-5000": ("world", "[12, 0]", f"[{BIG_5000}, 0]"),
    "world-wall-neg-330": ("world", "[12, 0]", f"[-{BIG_330}, 0]"),
    "world-start-330": ("world", "start: [1.0, 1.5, 0.0]", f"start: [1.0, 1.5, {BIG_330}]"),
    "world-radius-330": ("world", "radius: 0.25", f"radius: {BIG_330}"),
    "world-circle-330": ("world", "circle: [8.0, 0.6, 0.3]", f"circle: [8.0, 0.6, {BIG_330}]"),
    "world-date": ("world", "start: [1.0, 1.5, 0.0]", "start: 2001-13-45"),
    "table-weight-330": ("table", "avoid: 0.1,", f"avoid: {BIG_330},"),
    "table-weight-400": ("table", "avoid: 0.1,", f"avoid: {BIG_400},"),
    "table-default-330": ("table", "avoid: 0.4,", f"avoid: {BIG_330},"),
    "table-bac-330": ("table", "bac: 63", f"bac: {BIG_330}"),
    "table-samples-5000": ("table", "bac: 31", f"bac: 31\n          samples: {BIG_5000}"),
    "table-fit-string": ("table", "bac: 31", "bac: 31\n          fit_error_deg: lots"),
    "table-fit-quoted": ("table", "bac: 31", "bac: 31\n          fit_error_deg: '3.5'"),
    "table-fit-330": ("table", "bac: 31", f"bac: 31\n          fit_error_deg: {BIG_330}"),
    "table-fit-nan": ("table", "bac: 31", "bac: 31\n          fit_error_deg: .nan"),
    "table-low-samples-string": ("table", "bac: 31", "bac: 31\n          low_samples: maybe"),
    "task-target-330": ("task", "target: red", f"target: {BIG_330}"),
    "task-style-400": ("task", "style: keep-center", f"style: {BIG_400}"),
}

# --- mapping keys that are not names ---------------------------------------------------------

KEYS: dict[str, tuple[str, str, str]] = {
    "world-key-int": ("world", "name: box\n", "name: box\n1: x\n"),
    "world-keys-mixed": ("world", "name: box\n", "name: box\n1: x\nfloor: wood\n"),
    "world-key-null": ("world", "name: box\n", "name: box\n~: x\n"),
    "world-key-bool": ("world", "name: box\n", "name: box\nyes: x\n"),
    "world-key-list": ("world", "name: box\n", "name: box\n? [a, b]\n: x\n"),
    "world-key-big": ("world", "name: box\n", f"name: box\n{BIG_330}: x\n"),
    "world-target-key-int": ("world", "radius: 0.25}", "radius: 0.25, 7: 1, x: 2}"),
    "table-weights-key-int": ("table", "avoid: 0.1,", "1: 0.5, avoid: 0.1,"),
    "table-key-float": ("table", "format:", "1.5: x\nformat:"),
    "task-keys-mixed": ("task", "style: keep-center}", "style: keep-center, 3: 1, a: 2}"),
    "task-top-key-int": ("task", "task:", "5: x\ntask:"),
}

#: a merge key is a legitimate YAML key: it must still load
MERGE_WORLD = _replace(
    WORLD_YAML,
    "  - {name: red, position: [11.0, 1.5], radius: 0.25}\n",
    "  - &r {name: red, position: [11.0, 1.5], radius: 0.25}\n  - {<<: *r, name: blue}\n",
)


def _argv(kind: str) -> tuple[str, ...]:
    if kind == "world":
        return ("simulate", "--world", "w.yaml", "--duration", "1", "-o", "o.mcap")
    if kind == "table":
        return ("execute", "t.yaml", "--world", "corridor", "--max-time", "1", "-o", "r.mcap")
    return ("simulate", "--world", "w.yaml", "--teacher", "task.yaml", "--duration", "1", "-o", "o.mcap")


def _files(kind: str, text: str) -> dict[str, Content]:
    if kind == "world":
        return {"w.yaml": text}
    if kind == "table":
        return {"t.yaml": text}
    return {"task.yaml": text, "w.yaml": WORLD_YAML}


_BASE_TEXT = {"world": WORLD_YAML, "table": TABLE_YAML, "task": TASK_YAML}
_FILE = {"world": "w.yaml", "table": "t.yaml", "task": "task.yaml"}


def config_cases() -> Iterator[Case]:
    for family, variants in (("numbers", NUMBERS), ("keys", KEYS)):
        for name, (kind, old, new) in variants.items():
            text = _replace(_BASE_TEXT[kind], old, new)
            yield Case(f"{family}-{name}", "boundaries", _argv(kind), _files(kind, text), ERROR)
            yield Case(
                f"{family}-{name}-inspect", "boundaries", ("inspect", _FILE[kind]), _files(kind, text), ERROR
            )
    yield Case("keys-merge-ok", "boundaries", _argv("world"), {"w.yaml": MERGE_WORLD}, OK)
    for name, (kind, text) in {
        "numbers-valid-world": ("world", WORLD_YAML),
        "numbers-valid-table": ("table", TABLE_YAML),
        "numbers-float-literal-long": (
            "world",
            _replace(WORLD_YAML, "[12, 3]", "[12, 3." + "0" * 500 + "1]"),
        ),
    }.items():
        yield Case(name, "boundaries", _argv(kind), _files(kind, text), OK)


# --- weighted targets the world lacks (DESIGN §8) ----------------------------------------------

_TARGET_TABLE = """\
format: lfdfuse/fusion-table@1
behaviors: [avoid, wander_left, attract_purple]
default_weights: {default}
network:
  name: n
  steps:
{steps}"""
_LEAF = "    - name: s\n      goal: null\n{extra}      fusion:\n        - {{bac: 7, weights: {w}}}\n"
_NESTED = (
    "    - name: outer\n      goal: null\n      network:\n        name: inner\n        steps:\n"
    "          - name: s\n            goal: null\n            fusion:\n"
    "              - {{bac: 7, weights: {w}}}\n"
)
_PLAIN = "{avoid: 0.3, wander_left: 0.7}"
_PURPLE = "{avoid: 0.3, attract_purple: 0.7}"


def _target_table(*, default: str = _PLAIN, steps: str) -> str:
    return _TARGET_TABLE.format(default=default, steps=steps)


TARGETS: dict[str, tuple[str, frozenset[int]]] = {
    "unweighted": (_target_table(steps=_LEAF.format(extra="", w=_PLAIN)), OK),
    "zero-weight": (
        _target_table(steps=_LEAF.format(extra="", w="{avoid: 0.3, wander_left: 0.7, attract_purple: 0}")),
        OK,
    ),
    "weighted-row": (_target_table(steps=_LEAF.format(extra="", w=_PURPLE)), ERROR),
    "weighted-default": (_target_table(default=_PURPLE, steps=_LEAF.format(extra="", w=_PLAIN)), ERROR),
    "weighted-step-default": (
        _target_table(steps=_LEAF.format(extra=f"      default_weights: {_PURPLE}\n", w=_PLAIN)),
        ERROR,
    ),
    "weighted-nested": (_target_table(steps=_NESTED.format(w=_PURPLE)), ERROR),
    "goal-missing": (
        _target_table(steps=_LEAF.format(extra="", w=_PLAIN).replace("goal: null", "goal: {target: purple}")),
        OK,  # a goal the world lacks is never achieved; the step drives on (DESIGN §8)
    ),
}


def target_cases() -> Iterator[Case]:
    for name, (text, codes) in TARGETS.items():
        for world in ("corridor", "w.yaml"):
            argv = ("execute", "t.yaml", "--world", world, "--max-time", "1", "-o", "r.mcap")
            files: dict[str, Content] = {"t.yaml": text, "w.yaml": WORLD_YAML}
            yield Case(f"targets-{name}-{world.split('.')[0]}", "boundaries", argv, files, codes)
        teacher = ("simulate", "--world", "w.yaml", "--teacher", "t.yaml", "--duration", "1", "-o", "o.mcap")
        yield Case(
            f"targets-{name}-teacher", "boundaries", teacher, {"t.yaml": text, "w.yaml": WORLD_YAML}, codes
        )


# --- MCAP: lengths, sizes and times ---------------------------------------------------------

_CHUNK = 0x06


def _records(data: bytes) -> Iterator[tuple[int, int, int]]:
    """``(offset, opcode, length)`` of the data section's records."""
    pos = 8
    while pos + 9 <= len(data):
        opcode, length = struct.unpack_from("<BQ", data, pos)
        yield pos, opcode, length
        if opcode == 0x0F:
            return
        pos += 9 + length


def _first_chunk(data: bytes) -> tuple[int, int]:
    for pos, opcode, length in _records(data):
        if opcode == _CHUNK:
            return pos, length
    raise AssertionError("the base demo has no chunk")


def _patch(name: str, field: str, value: int, *, cut: bool = False) -> Callable[[Base], bytes]:
    """The base file with one u64 of its first chunk set to ``value`` (and the rest cut off)."""

    def make(b: Base) -> bytes:
        data = bytearray(b[name])
        pos, length = _first_chunk(bytes(data))
        if field == "record":
            struct.pack_into("<Q", data, pos + 1, value)
        elif field == "uncompressed":
            struct.pack_into("<Q", data, pos + 9 + 16, value)
        else:  # the chunk's data length: after start, end, size, crc and the compression string
            off = pos + 9 + 28
            (n,) = struct.unpack_from("<I", data, off)
            struct.pack_into("<Q", data, off + 4 + n, value)
        return bytes(data[: pos + 9 + length]) if cut else bytes(data)

    return make


def _unsized_chunk(uncompressed: int) -> Callable[[Base], bytes]:
    """A file of one zstd chunk whose frame has no content size, declaring ``uncompressed`` bytes
    (the decompressor then allocates what the chunk declares), and no summary."""

    def make(_b: Base) -> bytes:
        inner = RecordBuilder()
        Schema(id=1, name="foxglove.LaserScan", encoding="jsonschema", data=b"{}").write(inner)
        Schema(id=2, name="lfdfuse.Twist", encoding="jsonschema", data=b"{}").write(inner)
        Channel(id=1, topic="/scan", message_encoding="json", schema_id=1, metadata={}).write(inner)
        Channel(id=2, topic="/cmd_vel", message_encoding="json", schema_id=2, metadata={}).write(inner)
        for i, (topic, t, data) in enumerate(plain_log()):
            cid = 1 if topic == "/scan" else 2
            Message(channel_id=cid, sequence=i, log_time=t, publish_time=t, data=data).write(inner)
        raw = inner.end()
        size = len(raw) if uncompressed < 0 else uncompressed
        packed = zstandard.ZstdCompressor(write_content_size=False).compress(raw)
        out = RecordBuilder()
        Header(profile="", library="hostile").write(out)
        Chunk(
            message_start_time=0,
            message_end_time=plain_log()[-1][1],
            uncompressed_size=size,
            uncompressed_crc=0,
            compression="zstd",
            data=packed,
        ).write(out)
        DataEnd(data_section_crc=0).write(out)
        Footer(summary_start=0, summary_offset_start=0, summary_crc=0).write(out)
        return b"\x89MCAP0\r\n" + out.end() + b"\x89MCAP0\r\n"

    return make


def _late(t_ns: int, *, header: int | None = None) -> Callable[[Base], bytes]:
    msgs = plain_log()
    msgs[5] = ("/scan", t_ns, scan(t_ns if header is None else header, [1.0] * 181))
    return lambda _b: craft(msgs)


def _meta(**values: str) -> Callable[[Base], bytes]:
    return lambda _b: craft(plain_log(), metadata={"lfdfuse": dict(values)})


MCAPS: dict[str, tuple[Callable[[Base], bytes], frozenset[int]]] = {
    "chunk-record-huge": (_patch("demo.mcap", "record", 2**62), OK_OR_ERROR),
    "chunk-record-huge-cut": (_patch("demo.mcap", "record", 2**62, cut=True), ERROR),
    "chunk-data-huge": (_patch("demo.mcap", "data", 2**62), OK_OR_ERROR),
    "chunk-data-huge-cut": (_patch("demo.mcap", "data", 2**62, cut=True), ERROR),
    "chunk-data-u64max": (_patch("seg.mcap", "data", 2**64 - 1), OK_OR_ERROR),
    "chunk-uncompressed-huge": (_patch("demo.mcap", "uncompressed", 2**62), ERROR),
    "unsized-chunk-ok": (_unsized_chunk(-1), OK),
    "unsized-chunk-8gb": (_unsized_chunk(2**33), ERROR),
    "unsized-chunk-huge": (_unsized_chunk(2**62), ERROR),
    "log-time-u64max": (_late(2**64 - 1, header=0), ERROR),
    "log-time-int64max": (_late(2**63 - 1, header=0), OK_OR_ERROR),
    "stamp-u64max": (_late(1000, header=2**64 - 1), OK_OR_ERROR),
    "meta-range-word": (_meta(laser_max_range_m="far"), ERROR),
    "meta-range-nan": (_meta(laser_max_range_m="nan"), ERROR),
    "meta-range-zero": (_meta(laser_max_range_m="0"), ERROR),
    "meta-sonar-word": (_meta(sonar_max_range_m="far"), OK_OR_ERROR),  # no /sonar: never read
    "meta-range-number": (_meta(laser_max_range_m="8.0"), OK),
}


def mcap_cases() -> Iterator[Case]:
    for name, (content, codes) in MCAPS.items():
        # sizes in a process with a memory limit: an allocation of what a record claims would fail
        # (or swap) there instead of passing by overcommit
        sized = name.startswith(("chunk-", "unsized-"))
        yield Case(
            f"mcap-{name}",
            "boundaries",
            ("segment", "d.mcap"),
            {"d.mcap": content},
            codes,
            process=sized,
            mem_mb=2500 if sized else None,
        )
        yield Case(
            f"mcap-{name}-inspect", "boundaries", ("inspect", "d.mcap"), {"d.mcap": content}, OK_OR_ERROR
        )


# --- a long task is valid ----------------------------------------------------------------------


def task_cases() -> Iterator[Case]:
    legs = "task:\n" + "  - {target: red, style: keep-left}\n" * 10_000
    argv = ("simulate", "--world", "w.yaml", "--teacher", "task.yaml", "--duration", "1", "-o", "o.mcap")
    yield Case(
        "task-legs-10000", "boundaries", argv, {"task.yaml": legs, "w.yaml": WORLD_YAML}, OK, timeout_s=120
    )


def boundaries() -> Iterator[Case]:
    yield from config_cases()
    yield from target_cases()
    yield from mcap_cases()
    yield from task_cases()
