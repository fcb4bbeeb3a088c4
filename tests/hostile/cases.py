"""The hostile corpus, by class. Every generator is deterministic (seeded), so a failure reproduces.

``corpus()`` is the full set (``make fuzz``); ``sample()`` a slice of every class for ``make test``.
"""

from __future__ import annotations

import io
import os
import random
import signal
from collections.abc import Callable, Iterator
from pathlib import Path

import orjson
from mcap.reader import make_reader
from mcap.writer import CompressionType

from lfdfuse.log.lfd import SEGMENT_TOPICS
from lfdfuse.log.messages import TOPICS
from tests.hostile.base import Base, Msg, cmd, craft, plain_log, scan
from tests.hostile.boundaries import boundaries
from tests.hostile.runner import Case

OK_OR_ERROR = frozenset({0, 1})
ERROR = frozenset({1})
USAGE = frozenset({2})
INTERRUPTED = frozenset({130, 143})
AS_ROOT = os.geteuid() == 0

# --- byte-level damage to MCAP files --------------------------------------------------------


def _truncate(name: str, at: float) -> Callable[[Base], bytes]:
    def make(b: Base) -> bytes:
        data = b[name]
        cut = int(at * len(data)) if 0 < at < 1 else int(at) if at >= 0 else len(data) + int(at)
        return data[:cut]

    return make


def _flip(name: str, seed: int, bits: int) -> Callable[[Base], bytes]:
    def make(b: Base) -> bytes:
        rng = random.Random(seed)
        data = bytearray(b[name])
        for _ in range(bits):
            i = rng.randrange(len(data))
            data[i] ^= 1 << rng.randrange(8)
        return bytes(data)

    return make


def _zero(name: str, seed: int) -> Callable[[Base], bytes]:
    def make(b: Base) -> bytes:
        rng = random.Random(seed)
        data = bytearray(b[name])
        i = rng.randrange(len(data) - 512)
        data[i : i + 512] = bytes(512)
        return bytes(data)

    return make


def mcap_corrupt() -> Iterator[Case]:
    cuts = [0, 1, 8, 100, 0.25, 0.5, 0.9, -1, -30]
    for at in cuts:
        yield Case(
            f"demo-cut-{at}",
            "mcap_corrupt",
            ("segment", "d.mcap"),
            {"d.mcap": _truncate("demo.mcap", at)},
            OK_OR_ERROR,
        )
        yield Case(
            f"demo-cut-{at}-inspect",
            "mcap_corrupt",
            ("inspect", "d.mcap"),
            {"d.mcap": _truncate("demo.mcap", at)},
            OK_OR_ERROR,
        )
        yield Case(
            f"seg-cut-{at}",
            "mcap_corrupt",
            ("estimate", "s.mcap", "-o", "t.yaml"),
            {"s.mcap": _truncate("seg.mcap", at)},
            OK_OR_ERROR,
        )
    for seed in range(32):
        bits = 1 + seed % 4
        yield Case(
            f"demo-flip-{seed}",
            "mcap_corrupt",
            ("segment", "d.mcap"),
            {"d.mcap": _flip("demo.mcap", seed, bits)},
            OK_OR_ERROR,
        )
        if seed % 2 == 0:
            yield Case(
                f"seg-flip-{seed}",
                "mcap_corrupt",
                ("estimate", "s.mcap", "-o", "t.yaml"),
                {"s.mcap": _flip("seg.mcap", seed, bits)},
                OK_OR_ERROR,
            )
        if seed % 4 == 0:
            yield Case(
                f"demo-flip-{seed}-inspect",
                "mcap_corrupt",
                ("inspect", "d.mcap"),
                {"d.mcap": _flip("demo.mcap", seed, bits)},
                OK_OR_ERROR,
            )
    for seed in range(6):
        yield Case(
            f"demo-zero-{seed}",
            "mcap_corrupt",
            ("segment", "d.mcap"),
            {"d.mcap": _zero("demo.mcap", seed)},
            OK_OR_ERROR,
        )
        yield Case(
            f"seg-zero-{seed}",
            "mcap_corrupt",
            ("estimate", "s.mcap", "-o", "t.yaml"),
            {"s.mcap": _zero("seg.mcap", seed)},
            OK_OR_ERROR,
        )
    yield Case(
        "demo-garbage-tail",
        "mcap_corrupt",
        ("segment", "d.mcap"),
        {"d.mcap": lambda b: b["demo.mcap"] + os.urandom(0) + b"\x00garbage" * 100},
        OK_OR_ERROR,
    )
    yield Case(
        "demo-twice",
        "mcap_corrupt",
        ("segment", "d.mcap"),
        {"d.mcap": lambda b: b["demo.mcap"] * 2},
        OK_OR_ERROR,
    )


# --- right framing, wrong content -----------------------------------------------------------


def _log(messages: list[Msg], **kw: object) -> Callable[[Base], bytes]:
    return lambda b: craft(messages, **kw)  # type: ignore[arg-type]


def _with(replace: dict[str, Callable[[int], bytes]], n: int = 30, **kw: object) -> Callable[[Base], bytes]:
    msgs = [(topic, t, replace[topic](t) if topic in replace else data) for topic, t, data in plain_log(n)]
    return _log(msgs, **kw)


def mcap_schema() -> Iterator[Case]:
    plain = plain_log()
    variants: dict[str, tuple[Callable[[Base], bytes], frozenset[int]]] = {
        "valid": (_log(plain), frozenset({0})),
        "protobuf": (_log(plain, message_encoding="protobuf", schema_encoding="protobuf"), ERROR),
        "cdr": (_log(plain, message_encoding="cdr", schema_encoding="ros2msg"), ERROR),
        "ros-names": (_log(plain, schemas={"/scan": "sensor_msgs/msg/LaserScan"}), OK_OR_ERROR),
        "no-schema-encoding": (_log(plain, schema_encoding=""), OK_OR_ERROR),
        "uncompressed": (_log(plain, compression=CompressionType.NONE), frozenset({0})),
        "lz4": (_log(plain, compression=CompressionType.LZ4), OK_OR_ERROR),
        "no-ranges": (
            _with(
                {
                    "/scan": lambda t: orjson.dumps(
                        {"timestamp": {"sec": 0, "nsec": 0}, "start_angle": 0, "end_angle": 1}
                    )
                }
            ),
            ERROR,
        ),
        "ranges-strings": (_with({"/scan": lambda t: scan(t, ["a"] * 181)}), ERROR),
        "ranges-null": (_with({"/scan": lambda t: scan(t, [None] * 181)}), OK_OR_ERROR),
        "ranges-nested": (_with({"/scan": lambda t: scan(t, [[1.0]] * 181)}), ERROR),
        "ranges-dict": (_with({"/scan": lambda t: scan(t, {"a": 1})}), ERROR),  # type: ignore[arg-type]
        "ranges-huge": (_with({"/scan": lambda t: scan(t, [1e308] * 181)}), OK_OR_ERROR),
        "ranges-negative": (_with({"/scan": lambda t: scan(t, [-1.0] * 181)}), OK_OR_ERROR),
        "ranges-bool": (_with({"/scan": lambda t: scan(t, [True] * 181)}), OK_OR_ERROR),
        "angle-string": (_with({"/scan": lambda t: scan(t, [1.0] * 181, start="abc")}), ERROR),
        "angle-null": (_with({"/scan": lambda t: scan(t, [1.0] * 181, start=None)}), ERROR),
        "angle-huge": (
            _with({"/scan": lambda t: scan(t, [1.0] * 181, start=-1e300, end=1e300)}),
            OK_OR_ERROR,
        ),
        "angles-reversed": (
            _with({"/scan": lambda t: scan(t, [1.0] * 181, start=1.5, end=-1.5)}),
            OK_OR_ERROR,
        ),
        "beams-0": (_with({"/scan": lambda t: scan(t, [])}), ERROR),
        "beams-1": (_with({"/scan": lambda t: scan(t, [1.0])}), OK_OR_ERROR),
        "beams-2": (_with({"/scan": lambda t: scan(t, [1.0, 2.0])}), OK_OR_ERROR),
        "beams-mixed": (_log(plain + [("/scan", 5_000_000_000, scan(5_000_000_000, [1.0] * 90))]), ERROR),
        "cmd-string": (_with({"/cmd_vel": lambda t: cmd(t, "fast")}), ERROR),
        "cmd-null": (_with({"/cmd_vel": lambda t: cmd(t, None)}), ERROR),
        "cmd-huge": (_with({"/cmd_vel": lambda t: cmd(t, 1e308, -1e308)}), OK_OR_ERROR),
        "cmd-missing": (_with({"/cmd_vel": lambda t: orjson.dumps({"linear": {}})}), ERROR),
        "cmd-list": (_with({"/cmd_vel": lambda t: b"[1, 2, 3]"}), ERROR),
        "payload-not-json": (_with({"/scan": lambda t: b"\x00\xff\xfe not json"}), ERROR),
        "payload-not-utf8": (_with({"/cmd_vel": lambda t: b'{"linear": {"x": "\xff"}}'}), ERROR),
        "payload-number": (_with({"/scan": lambda t: b"42"}), ERROR),
        "payload-deep": (_with({"/scan": lambda t: b"[" * 5000 + b"]" * 5000}), ERROR),
        "payload-empty": (_with({"/cmd_vel": lambda t: b""}), ERROR),
        "no-cmd": (_log([m for m in plain if m[0] == "/scan"]), ERROR),
        "no-scan": (_log([m for m in plain if m[0] == "/cmd_vel"]), ERROR),
        "empty": (_log([]), ERROR),
        "one-scan": (_log(plain_log(1)), OK_OR_ERROR),
        "epoch": (_log(plain_log(t0=1_700_000_000_123_456_789)), frozenset({0})),
        "int64-max": (_log(plain_log(t0=2**63 - 10**10)), OK_OR_ERROR),
        "same-time": (_log(plain_log(dt=0)), OK_OR_ERROR),
        "backwards": (_log(list(reversed(plain))), OK_OR_ERROR),
        "shuffled": (_log(random.Random(1).sample(plain, len(plain))), OK_OR_ERROR),
        "gap-year": (_log(plain_log(15) + plain_log(15, t0=365 * 86400 * 10**9)), OK_OR_ERROR),
        "meta-garbage": (
            _log(
                plain,
                metadata={
                    "lfdfuse": {
                        "laser_max_range_m": "abc",
                        "camera_reach_m": "nan",
                        "sonar_max_range_m": "-1",
                    }
                },
            ),
            OK_OR_ERROR,
        ),
        "meta-inf": (
            _log(plain, metadata={"lfdfuse": {"laser_max_range_m": "inf", "camera_reach_m": "1e308"}}),
            OK_OR_ERROR,
        ),
        "world-bad-yaml": (_log(plain, attachments=[("world.yaml", b"walls: [[[")]), OK_OR_ERROR),
        "world-bomb": (_log(plain, attachments=[("world.yaml", _BOMB.encode())]), OK_OR_ERROR),
        "world-not-utf8": (_log(plain, attachments=[("world.yaml", b"\xff\xfe\x00")]), OK_OR_ERROR),
        "world-huge-target": (_log(plain, attachments=[("world.yaml", _huge_target_world())]), OK_OR_ERROR),
        "targets-wrong": (_log(plain + [("/targets", 0, b'{"detections": [{"name": 5}]}')]), OK_OR_ERROR),
        "targets-huge-name": (
            _log(
                plain
                + [
                    (
                        "/targets",
                        0,
                        orjson.dumps(
                            {"detections": [{"name": "x" * 200_000, "bearing_rad": 0, "range_m": 1}]}
                        ),
                    )
                ]
            ),
            OK_OR_ERROR,
        ),
        "pose-wrong": (
            _log(plain + [("/pose", 0, b'{"pose": 1}')], schemas={"/pose": "foxglove.PoseInFrame"}),
            OK_OR_ERROR,
        ),
        "sonar-wrong": (_log(plain + [("/sonar", 0, scan(0, ["x"]))]), OK_OR_ERROR),
    }
    for name, (content, codes) in variants.items():
        yield Case(name, "mcap_schema", ("segment", "d.mcap"), {"d.mcap": content}, codes)
        yield Case(f"{name}-inspect", "mcap_schema", ("inspect", "d.mcap"), {"d.mcap": content}, OK_OR_ERROR)
    # sizes that could blow up: in a process with a memory limit
    big = [("/scan", i * 10**8, scan(i * 10**8, [1.0] * 100_000)) for i in range(3)] + [
        ("/cmd_vel", 0, cmd(0))
    ]
    yield Case(
        "beams-100000",
        "mcap_schema",
        ("segment", "d.mcap"),
        {"d.mcap": _log(big)},
        ERROR,
        process=True,
        mem_mb=2500,
    )


_BOMB = "\n".join(
    ["a: &a [x, x, x, x, x, x, x, x, x]"]
    + [f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join([f'*{chr(97 + i)}'] * 9)}]" for i in range(8)]
)


def _huge_target_world() -> bytes:
    name = "r" * 5_000_000
    return f"name: w\nwalls: [[[0, 0], [5, 0], [5, 5], [0, 5], [0, 0]]]\ntargets: [{{name: {name}, position: [1, 1]}}]\nstart: [2, 2, 0]\n".encode()


# --- segmented logs with broken /lfd/* content -----------------------------------------------


def _seg_messages(b: Base) -> list[tuple[str, int, dict | bytes]]:  # type: ignore[type-arg]
    out: list[tuple[str, int, dict | bytes]] = []  # type: ignore[type-arg]
    for _s, ch, m in make_reader(io.BytesIO(b["seg.mcap"])).iter_messages(log_time_order=True):
        out.append((ch.topic, m.log_time, orjson.loads(m.data) if ch.topic.startswith("/lfd/") else m.data))
    return out


Mutator = Callable[[str, int, int, dict], object]  # type: ignore[type-arg]


def _seg(mutate: Mutator, *, drop: str | None = None) -> Callable[[Base], bytes]:
    def make(b: Base) -> bytes:
        msgs: list[Msg] = []
        counts: dict[str, int] = {}
        for topic, t, data in _seg_messages(b):
            if topic == drop:
                continue
            if isinstance(data, dict):
                i = counts[topic] = counts.get(topic, -1) + 1
                new = mutate(topic, i, t, data)
                if new is None:
                    continue
                payload = new if isinstance(new, bytes) else orjson.dumps(new)
            else:
                payload = data
            msgs.append((topic, t, payload))
        return craft(msgs, schemas={**TOPICS, **SEGMENT_TOPICS})

    return make


def _on(topic: str, change: Callable[[int, dict], object]) -> Mutator:  # type: ignore[type-arg]
    return lambda tp, i, t, d: change(i, d) if tp == topic else d


def _set(d: dict, path: tuple[object, ...], value: object) -> dict:  # type: ignore[type-arg]
    d = orjson.loads(orjson.dumps(d))
    cur = d
    for k in path[:-1]:
        cur = cur[k]  # type: ignore[index]
    cur[path[-1]] = value  # type: ignore[index]
    return d


def seg_broken() -> Iterator[Case]:
    B, D, C, S = "/lfd/behaviors", "/lfd/demo", "/lfd/bac", "/lfd/segment"
    variants: dict[str, Callable[[Base], bytes]] = {
        "valid": _seg(lambda tp, i, t, d: d),
        "no-behaviors-key": _seg(_on(B, lambda i, d: {"timestamp": d["timestamp"]})),
        "behaviors-not-list": _seg(_on(B, lambda i, d: _set(d, ("behaviors",), 5))),
        "behaviors-empty": _seg(_on(B, lambda i, d: _set(d, ("behaviors",), []))),
        "x-string": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 0, "x"), "left"))),
        "x-null": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 0, "x"), None))),
        "x-huge": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 1, "x"), 1e300))),
        "x-nested": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 0, "x"), [1, [2]]))),
        "applicable-string": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 0, "applicable"), "no"))),
        "name-number": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 0, "name"), 7))),
        "name-unknown": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 0, "name"), "teleport"))),
        "name-huge": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 0, "name"), "a" * 100_000))),
        "names-change": _seg(
            _on(B, lambda i, d: _set(d, ("behaviors", 0, "name"), "wander") if i == 7 else d)
        ),
        "many-behaviors": _seg(_on(B, lambda i, d: _set(d, ("behaviors",), d["behaviors"] * 40))),
        "bac-string": _seg(_on(C, lambda i, d: _set(d, ("bac",), "x"))),
        "bac-negative": _seg(_on(C, lambda i, d: _set(d, ("bac",), -3))),
        "bac-huge": _seg(_on(C, lambda i, d: _set(d, ("bac",), 2**62))),
        "bac-float": _seg(_on(C, lambda i, d: _set(d, ("bac",), 1.5))),
        "demo-missing-x": _seg(_on(D, lambda i, d: {k: v for k, v in d.items() if k != "x"})),
        "demo-zero": _seg(_on(D, lambda i, d: _set(_set(d, ("x",), 0.0), ("y",), 0.0))),
        "demo-huge": _seg(_on(D, lambda i, d: _set(d, ("x",), 1e308))),
        "demo-informative-str": _seg(_on(D, lambda i, d: _set(d, ("informative",), "maybe"))),
        "demo-none-informative": _seg(_on(D, lambda i, d: _set(d, ("informative",), False))),
        "segment-noncontiguous": _seg(_on(S, lambda i, d: _set(d, ("index",), i % 2))),
        "segment-negative": _seg(_on(S, lambda i, d: _set(d, ("index",), -1))),
        "segment-huge": _seg(_on(S, lambda i, d: _set(d, ("index",), 10**15 + i))),
        "segment-goal-number": _seg(_on(S, lambda i, d: _set(d, ("goal",), 3))),
        "segment-goal-unknown": _seg(_on(S, lambda i, d: _set(d, ("goal",), "attract_nowhere"))),
        "drop-demo": _seg(lambda tp, i, t, d: d, drop=D),
        "drop-bac": _seg(lambda tp, i, t, d: d, drop=C),
        "drop-segment": _seg(lambda tp, i, t, d: d, drop=S),
        "drop-behaviors": _seg(lambda tp, i, t, d: d, drop=B),
        "drop-half-demo": _seg(lambda tp, i, t, d: None if tp == D and i % 2 else d),
        "payload-garbage": _seg(_on(B, lambda i, d: b"\xff" if i == 3 else d)),
        "payload-array": _seg(_on(D, lambda i, d: [1, 2])),
        "payload-deep": _seg(_on(C, lambda i, d: b"[" * 3000 + b"]" * 3000 if i == 2 else d)),
        "x-numeric-string": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 0, "x"), "0.5"))),
        "goal-met-int": _seg(_on(B, lambda i, d: _set(d, ("behaviors", 0, "goal_met"), 0))),
        "extra-field": _seg(_on(D, lambda i, d: {**d, "speed": 1.0})),
    }
    for name, content in variants.items():
        yield Case(
            name, "seg_broken", ("estimate", "s.mcap", "-o", "t.yaml"), {"s.mcap": content}, OK_OR_ERROR
        )
        if name in ("valid", "names-change", "segment-noncontiguous", "x-string", "drop-demo", "bac-huge"):
            yield Case(
                f"{name}-inspect", "seg_broken", ("inspect", "s.mcap"), {"s.mcap": content}, OK_OR_ERROR
            )


# --- worlds ----------------------------------------------------------------------------------

_BOX = "walls: [[[0, 0], [12, 0], [12, 3], [0, 3], [0, 0]]]\n"


def _deep(n: int) -> str:
    return "walls: " + "[" * n + "]" * n + "\nstart: [1, 1, 0]\n"


WORLDS: dict[str, tuple[Content, frozenset[int]]] = {}


def _worlds() -> dict[str, tuple[bytes | str, frozenset[int]]]:
    many = (
        "walls:\n"
        + "".join(f"  - [[{i % 500}, {i // 500}], [{i % 500}.5, {i // 500}]]\n" for i in range(250_000))
        + "start: [0.2, 0.2, 0]\n"
    )
    return {
        "valid": (_BOX + "start: [1, 1.5, 0]\n", frozenset({0})),
        "empty": ("", ERROR),
        "null": ("null\n", ERROR),
        "list": ("- 1\n- 2\n", ERROR),
        "scalar": ("42\n", ERROR),
        "unknown-key": (_BOX + "start: [1, 1.5, 0]\nfloor: wood\n", ERROR),
        "no-walls": ("start: [1, 1, 0]\n", ERROR),
        "no-start": (_BOX, OK_OR_ERROR),
        "walls-string": ("walls: lots\nstart: [1, 1, 0]\n", ERROR),
        "walls-number": ("walls: 5\nstart: [1, 1, 0]\n", ERROR),
        "walls-empty": ("walls: []\nstart: [1, 1, 0]\n", ERROR),
        "wall-one-point": ("walls: [[[0, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "wall-degenerate": ("walls: [[[0, 0], [0, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "wall-collinear-closed": ("walls: [[[0, 0], [5, 0], [0, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "wall-3d": ("walls: [[[0, 0, 0], [5, 0, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "wall-string-coord": ("walls: [[[0, a], [5, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "wall-bool-coord": ("walls: [[[0, true], [5, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "wall-nan": ("walls: [[[0, .nan], [5, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "wall-inf": ("walls: [[[0, 0], [.inf, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "coords-1e6": (
            "walls: [[[0, 0], [1000000, 0], [1000000, 1000000], [0, 1000000], [0, 0]]]\nstart: [1, 1, 0]\n",
            ERROR,
        ),
        "coords-1e12": ("walls: [[[0, 0], [1e12, 0], [1e12, 3], [0, 3], [0, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "coords-far-offset": ("walls: [[[1e9, 0], [1.00000001e9, 0]]]\nstart: [1, 1, 0]\n", ERROR),
        "coords-tiny": ("walls: [[[0, 0], [1e-9, 0], [1e-9, 1e-9], [0, 0]]]\nstart: [0, 0, 0]\n", ERROR),
        "start-outside": (_BOX + "start: [50, 50, 0]\n", ERROR),
        "start-in-wall": (_BOX + "start: [0, 1, 0]\n", ERROR),
        "start-string": (_BOX + "start: here\n", ERROR),
        "start-short": (_BOX + "start: [1, 1]\n", ERROR),
        "start-nan": (_BOX + "start: [.nan, 1, 0]\n", ERROR),
        "start-huge-theta": (_BOX + "start: [1, 1.5, 1e300]\n", OK_OR_ERROR),
        "target-huge-name": (
            _BOX + "start: [1, 1.5, 0]\ntargets: [{name: " + "r" * 1_000_000 + ", position: [3, 1]}]\n",
            ERROR,
        ),
        "target-bad-name": (_BOX + "start: [1, 1.5, 0]\ntargets: [{name: 'a b', position: [3, 1]}]\n", ERROR),
        "target-dup": (
            _BOX
            + "start: [1, 1.5, 0]\ntargets: [{name: a, position: [3, 1]}, {name: a, position: [4, 1]}]\n",
            ERROR,
        ),
        "target-radius-neg": (
            _BOX + "start: [1, 1.5, 0]\ntargets: [{name: a, position: [3, 1], radius: -1}]\n",
            ERROR,
        ),
        "target-radius-huge": (
            _BOX + "start: [1, 1.5, 0]\ntargets: [{name: a, position: [3, 1], radius: 1e9}]\n",
            ERROR,
        ),
        "target-position-str": (_BOX + "start: [1, 1.5, 0]\ntargets: [{name: a, position: here}]\n", ERROR),
        "target-outside": (_BOX + "start: [1, 1.5, 0]\ntargets: [{name: a, position: [1e5, 1e5]}]\n", ERROR),
        "targets-many": (
            _BOX
            + "start: [1, 1.5, 0]\ntargets: ["
            + ", ".join(f"{{name: t{i}, position: [3, 1]}}" for i in range(5000))
            + "]\n",
            ERROR,
        ),
        "obstacle-radius-0": (_BOX + "start: [1, 1.5, 0]\nobstacles: [{circle: [5, 1, 0]}]\n", ERROR),
        "obstacle-radius-huge": (_BOX + "start: [1, 1.5, 0]\nobstacles: [{circle: [5, 1, 1e9]}]\n", ERROR),
        "obstacle-polygon-2": (
            _BOX + "start: [1, 1.5, 0]\nobstacles: [{polygon: [[1, 1], [2, 2]]}]\n",
            ERROR,
        ),
        "obstacle-bowtie": (
            _BOX + "start: [1, 1.5, 0]\nobstacles: [{polygon: [[4, 0.5], [6, 2.5], [6, 0.5], [4, 2.5]]}]\n",
            ERROR,
        ),
        "obstacle-unknown": (_BOX + "start: [1, 1.5, 0]\nobstacles: [{square: [1, 1, 1]}]\n", ERROR),
        "obstacles-many": (
            _BOX
            + "start: [1, 1.5, 0]\nobstacles: ["
            + ", ".join("{circle: [6, 1.5, 0.1]}" for _ in range(20_000))
            + "]\n",
            ERROR,
        ),
        "name-dict": ("name: {a: 1}\n" + _BOX + "start: [1, 1.5, 0]\n", ERROR),
        "description-list": ("description: [1, 2]\n" + _BOX + "start: [1, 1.5, 0]\n", ERROR),
        "deep-nesting": (_deep(100_000), ERROR),
        "deep-mapping": ("walls: " + "{a: " * 5000 + "1" + "}" * 5000 + "\n", ERROR),
        "anchor-bomb": (_BOMB + "\nwalls: *i\nstart: [1, 1, 0]\n", ERROR),
        "python-tag": ("!!python/object/apply:os.system ['true']\n", ERROR),
        "syntax": ("walls: [[[0, 0], [1, 0]]\nstart: [1, 1\n", ERROR),
        "tabs": ("walls:\n\t- [[0, 0], [1, 0]]\n", ERROR),
        "not-utf8": (b"name: \xff\xfe\nwalls: []\n", ERROR),
        "png": (b"\x89PNG\r\n\x1a\n" + bytes(200), ERROR),
        "nul-bytes": (b"walls: \x00\x00\x00\n", ERROR),
        "big-file": ("# " + "x" * 40_000_000 + "\n" + _BOX + "start: [1, 1.5, 0]\n", ERROR),
        "many-walls": (many, ERROR),
        "duplicate-keys": (_BOX + _BOX + "start: [1, 1.5, 0]\n", OK_OR_ERROR),
        "map-missing-image": (
            "image: nope.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
            ERROR,
        ),
        "map-bad-resolution": (
            "image: nope.pgm\nresolution: -1\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
            ERROR,
        ),
    }


def worlds() -> Iterator[Case]:
    heavy = {
        "coords-1e6",
        "coords-1e12",
        "anchor-bomb",
        "deep-nesting",
        "big-file",
        "many-walls",
        "obstacles-many",
        "target-huge-name",
        "obstacle-radius-huge",
        "target-radius-huge",
    }
    for name, (text, codes) in _worlds().items():
        argv = ("simulate", "--world", "w.yaml", "--duration", "1", "-o", "o.mcap")
        yield Case(
            name,
            "world",
            argv,
            {"w.yaml": text},
            codes,
            process=name in heavy,
            mem_mb=2500 if name in heavy else None,
            timeout_s=60,
        )
        if name in (
            "valid",
            "start-outside",
            "wall-degenerate",
            "anchor-bomb",
            "coords-1e6",
            "unknown-key",
            "not-utf8",
        ):
            exe = ("execute", "t.yaml", "--world", "w.yaml", "--max-time", "1", "-o", "r.mcap")
            yield Case(
                f"{name}-execute",
                "world",
                exe,
                {"w.yaml": text, "t.yaml": lambda b: b["table.yaml"]},
                codes,
                process=name in heavy,
                mem_mb=2500 if name in heavy else None,
            )
    for special in ("dir", "fifo", "missing", "devnull"):
        yield Case(
            f"world-{special}",
            "world",
            ("simulate", "--world", _special_path(special), "--duration", "1", "-o", "o.mcap"),
            {},
            ERROR,
            process=special == "fifo",
            setup=_special_setup(special),
            timeout_s=30,
        )


def _special_path(kind: str) -> str:
    return {"dir": "w.yaml", "fifo": "w.yaml", "missing": "nope.yaml", "devnull": "/dev/null"}[kind]


def _special_setup(kind: str) -> Callable[[Path], None] | None:
    if kind == "dir":
        return lambda d: (d / "w.yaml").mkdir()
    if kind == "fifo":
        return lambda d: os.mkfifo(d / "w.yaml")
    return None


# --- command-line values ---------------------------------------------------------------------


def cli_values() -> Iterator[Case]:
    sim = ("simulate", "--world", "corridor", "--duration", "1", "-o", "o.mcap")
    # option ranges are typer's: out of range is a usage error, exit 2
    sim_cases: list[tuple[tuple[str, ...], frozenset[int]]] = [
        (("--seed", "-1"), USAGE),
        (("--seed", str(2**64)), USAGE),
        (("--seed", "1.5"), USAGE),
        (("--seed", "x"), USAGE),
        (("--duration", "nan"), USAGE),
        (("--duration", "inf"), USAGE),
        (("--duration", "-5"), USAGE),
        (("--duration", "0"), USAGE),
        (("--duration", "1e12"), USAGE),
        (("--duration", "1e-9"), USAGE),
        (("--duration", "abc"), USAGE),
        (("--heading-noise", "inf"), USAGE),
        (("--heading-noise", "-5"), USAGE),
        (("--heading-noise", "nan"), USAGE),
        (("--heading-noise", "1e9"), USAGE),
        (("--heading-noise", "0"), frozenset({0})),
        (("--sensor-noise", "-1"), USAGE),
        (("--sensor-noise", "inf"), USAGE),
        (("--sensor-noise", "nan"), USAGE),
        (("--sensor-noise", "1e9"), USAGE),
        (("--sensor-noise", "0.05"), frozenset({0})),
        (("--start", "1,2"), USAGE),
        (("--start", "a,b,c"), USAGE),
        (("--start", "nan,1,0"), USAGE),
        (("--start", "1e300,0,0"), ERROR),
        (("--start", "1,1,1,1"), USAGE),
        (("--start", ""), USAGE),
        (("--start", "1;1.2;0"), USAGE),
        (("--start", "1 1.2 0"), USAGE),
        (("--start", "0,0,0"), ERROR),
        (("--start", "100,100,0"), ERROR),
        (("--start", " 1, 1.2 ,0"), frozenset({0})),
        (("--start", "1,1.2,1e300"), OK_OR_ERROR),
        (("--teacher", "bogus"), ERROR),
        (("--teacher", "nope.yaml"), ERROR),
        (("--teacher", ""), ERROR),
        (("--world", ""), ERROR),
        (("--world", "x" * 5000), ERROR),
        (("--bogus",), USAGE),
    ]
    for extra, codes in sim_cases:
        yield Case(f"simulate {' '.join(extra)}"[:80], "cli", sim + extra, {}, codes)
    seg = ("segment", "d.mcap", "-o", "s.mcap")
    for extra, codes in [
        (("--lag", "-1"), USAGE),
        (("--lag", "nan"), USAGE),
        (("--lag", "inf"), USAGE),
        (("--lag", "1e9"), USAGE),
        (("--lag", "1e-12"), frozenset({0})),
        (("--behaviors", ""), ERROR),
        (("--behaviors", "nope"), ERROR),
        (("--behaviors", ",,,"), ERROR),
        (("--behaviors", "avoid,avoid"), OK_OR_ERROR),
        (("--behaviors", "attract_red"), ERROR),
        (("--behaviors", "full"), frozenset({0})),
        (("--behaviors", "avoid," * 5000), OK_OR_ERROR),
    ]:
        yield Case(
            f"segment {' '.join(extra)}"[:80], "cli", seg + extra, {"d.mcap": lambda b: b["demo.mcap"]}, codes
        )
    est = ("estimate", "s.mcap", "-o", "t.yaml")
    for extra, codes in [
        (("--particles", "0"), USAGE),
        (("--particles", "-1"), USAGE),
        (("--particles", "1000000000"), USAGE),
        (("--particles", "1"), OK_OR_ERROR),
        (("--trials", "0"), USAGE),
        (("--trials", "-3"), USAGE),
        (("--trials", "100000000"), USAGE),
        (("--method", "bogus"), USAGE),
        (("--likelihood", "bogus"), USAGE),
        (("--seed", "-1"), USAGE),
        (("--method", "nnls"), frozenset({0})),
        (("--method", "arbitration"), frozenset({0})),
    ]:
        yield Case(
            f"estimate {' '.join(extra)}"[:80], "cli", est + extra, {"s.mcap": lambda b: b["seg.mcap"]}, codes
        )
    exe = ("execute", "t.yaml", "--world", "corridor", "-o", "r.mcap")
    for extra, codes in [
        (("--max-time", "0"), USAGE),
        (("--max-time", "-1"), USAGE),
        (("--max-time", "nan"), USAGE),
        (("--max-time", "inf"), USAGE),
        (("--max-time", "1e12"), USAGE),
        (("--max-time", "1"), frozenset({0})),
        (("--max-time", "1", "--seed", "-1"), USAGE),
        (("--max-time", "1", "--sensor-noise", "-1"), USAGE),
        (("--max-time", "1", "--start", "1,2"), USAGE),
        (("--max-time", "1", "--start", "0,0,0"), ERROR),
        (("--max-time", "1", "--report", "r.json"), frozenset({0})),
    ]:
        yield Case(
            f"execute {' '.join(extra)}"[:80],
            "cli",
            exe + extra,
            {"t.yaml": lambda b: b["table.yaml"]},
            codes,
        )
    # choices are enums typer offers: a bad one is a usage error before any file is read
    for argv in [
        ("import", "log.bag", "--format", "bogus"),
        ("import", "log.bag", "--format", ""),
        ("import", "log.bag", "--cmd-from", "bogus"),
        ("import", "log.bag", "--teacher", "robot"),
        ("teleop", "--input", "joystick", "-o", "t.mcap"),
        ("teleop", "--input", "script", "--port", "70000", "-o", "t.mcap"),
        ("teleop", "--input", "script", "--timeout", "0", "-o", "t.mcap"),
        ("teleop", "--input", "script", "--timeout", "nan", "-o", "t.mcap"),
        ("teleop", "--input", "script", "--duration", "-1", "-o", "t.mcap"),
        ("teleop", "--input", "script", "--seed", "-1", "-o", "t.mcap"),
        ("plot", "t.yaml", "-o", "p.png", "--whiskers", "nope"),
        ("evaluate", "s.mcap", "--seed", str(2**63)),
    ]:
        yield Case(
            " ".join(argv)[:80],
            "cli",
            argv,
            {"log.bag": b"not a bag", "t.yaml": lambda b: b["table.yaml"], "s.mcap": lambda b: b["seg.mcap"]},
            USAGE,
        )
    yield Case("no-args", "cli", (), {}, frozenset({0, 2}))
    yield Case("version", "cli", ("--version",), {}, frozenset({0}))
    yield Case("inspect-no-file", "cli", ("inspect",), {}, USAGE)
    yield Case("unknown-command", "cli", ("fly",), {}, USAGE)


# --- fusion tables ---------------------------------------------------------------------------


def _table(**over: str) -> str:
    parts = {
        "format": "format: lfdfuse/fusion-table@1\n",
        "behaviors": "behaviors: [avoid, wander_left, wander_right, wall_attract_left, wall_attract_right, sonar_avoid]\n",
        "default": "default_weights: {avoid: 0.4, wander_left: 0.3, wander_right: 0.3}\n",
        "network": "network:\n  name: n\n  steps:\n    - name: s\n      goal: null\n      fusion:\n        - {bac: 63, weights: {avoid: 0.2, wander_left: 0.8}}\n",
    }
    parts.update(over)
    return "".join(parts.values())


def _nested_table(depth: int) -> str:
    net = "{name: leaf, steps: [{name: s, goal: null, fusion: [{bac: 1, weights: {avoid: 1.0}}]}]}"
    for i in range(depth):
        net = f"{{name: n{i}, steps: [{{name: s{i}, goal: null, network: {net}}}]}}"
    return _table(network=f"network: {net}\n")


def _tables() -> dict[str, tuple[bytes | str, frozenset[int]]]:
    fusion = "network:\n  name: n\n  steps:\n    - name: s\n      goal: null\n      fusion:\n        - {{bac: {bac}, weights: {w}}}\n"
    return {
        "valid": (_table(), frozenset({0})),
        "empty": ("", ERROR),
        "list": ("[1, 2]\n", ERROR),
        "scalar": ("fusion\n", ERROR),
        "no-format": (_table(format=""), ERROR),
        "wrong-format": (_table(format="format: lfdfuse/fusion-table@9\n"), ERROR),
        "format-number": (_table(format="format: 1\n"), ERROR),
        "unknown-top-key": (_table() + "colour: red\n", ERROR),
        "behaviors-string": (_table(behaviors="behaviors: avoid\n"), ERROR),
        "behaviors-empty": (_table(behaviors="behaviors: []\n"), ERROR),
        "behaviors-unknown": (_table(behaviors="behaviors: [avoid, teleport]\n"), ERROR),
        "behaviors-dup": (_table(behaviors="behaviors: [avoid, avoid]\n"), ERROR),
        "behaviors-numbers": (_table(behaviors="behaviors: [1, 2]\n"), ERROR),
        "behaviors-100": (_table(behaviors="behaviors: [" + ", ".join(["avoid"] * 100) + "]\n"), ERROR),
        "default-negative": (_table(default="default_weights: {avoid: -1}\n"), ERROR),
        "default-missing": (_table(default=""), OK_OR_ERROR),
        "default-unknown": (_table(default="default_weights: {teleport: 1}\n"), ERROR),
        "weight-negative": (_table(network=fusion.format(bac=63, w="{avoid: -0.5, wander_left: 1}")), ERROR),
        "weight-nan": (_table(network=fusion.format(bac=63, w="{avoid: .nan}")), ERROR),
        "weight-inf": (_table(network=fusion.format(bac=63, w="{avoid: .inf}")), ERROR),
        "weight-string": (_table(network=fusion.format(bac=63, w="{avoid: lots}")), ERROR),
        "weight-bool": (_table(network=fusion.format(bac=63, w="{avoid: true}")), ERROR),
        "weight-huge": (
            _table(network=fusion.format(bac=63, w="{avoid: 1e308, wander_left: 1e308}")),
            OK_OR_ERROR,
        ),
        "weights-zero": (_table(network=fusion.format(bac=63, w="{avoid: 0}")), OK_OR_ERROR),
        "weights-unknown": (_table(network=fusion.format(bac=63, w="{teleport: 1}")), ERROR),
        "weights-list": (_table(network=fusion.format(bac=63, w="[1, 2]")), ERROR),
        "bac-negative": (_table(network=fusion.format(bac=-1, w="{avoid: 1}")), ERROR),
        "bac-huge": (_table(network=fusion.format(bac=2**100, w="{avoid: 1}")), ERROR),
        "bac-string": (_table(network=fusion.format(bac="x", w="{avoid: 1}")), ERROR),
        "bac-float": (_table(network=fusion.format(bac=1.5, w="{avoid: 1}")), ERROR),
        "steps-empty": (_table(network="network: {name: n, steps: []}\n"), ERROR),
        "steps-missing": (_table(network="network: {name: n}\n"), ERROR),
        "network-list": (_table(network="network: [1]\n"), ERROR),
        "step-both": (
            _table(
                network="network: {name: n, steps: [{name: s, goal: null, fusion: [], network: {name: m, steps: []}}]}\n"
            ),
            ERROR,
        ),
        "step-neither": (_table(network="network: {name: n, steps: [{name: s, goal: null}]}\n"), ERROR),
        "step-unknown-key": (
            _table(network="network: {name: n, steps: [{name: s, goal: null, fusion: [], speed: 3}]}\n"),
            ERROR,
        ),
        "goal-number": (
            _table(network="network: {name: n, steps: [{name: s, goal: 5, fusion: []}]}\n"),
            ERROR,
        ),
        # DESIGN §8: a goal the world lacks is never achieved, its step drives on (exit 0 since
        # 64a8c6d; only weighted attract behaviours need their targets: boundaries.py)
        "goal-unknown-target": (
            _table(network="network: {name: n, steps: [{name: s, goal: {target: purple}, fusion: []}]}\n"),
            frozenset({0}),
        ),
        "nested-ok": (_nested_table(3), frozenset({0})),
        "nested-deep": (_nested_table(200), ERROR),
        "deep-yaml": ("a: " + "[" * 50_000 + "]" * 50_000 + "\n", ERROR),
        "anchor-bomb": (_BOMB + "\nformat: *i\n", ERROR),
        "not-utf8": (b"format: \xff\n", ERROR),
        "big-file": ("# " + "x" * 40_000_000 + "\n" + _table(), ERROR),
        "rows-many": (
            _table(
                network="network:\n  name: n\n  steps:\n    - name: s\n      goal: null\n      fusion:\n"
                + "".join(f"        - {{bac: {i}, weights: {{avoid: 1}}}}\n" for i in range(1, 64, 2))
            ),
            frozenset({0}),
        ),
        "std-negative": (
            _table(
                network="network: {name: n, steps: [{name: s, goal: null, fusion: [{bac: 1, weights: {avoid: 1}, std: {avoid: -1}}]}]}\n"
            ),
            ERROR,
        ),
        "samples-string": (
            _table(
                network="network: {name: n, steps: [{name: s, goal: null, fusion: [{bac: 1, weights: {avoid: 1}, samples: many}]}]}\n"
            ),
            ERROR,
        ),
        # the README's newcomer case: a target behaviour without weight needs no target in the world
        "unweighted-target": (
            _table(
                behaviors="behaviors: [avoid, attract_red, wander_left, wander_right]\n",
                network=fusion.format(bac=13, w="{avoid: 0.3, wander_left: 0.7}"),
            ),
            frozenset({0}),
        ),
        "weighted-target-missing": (
            _table(
                behaviors="behaviors: [avoid, attract_red, wander_left, wander_right]\n",
                network=fusion.format(bac=3, w="{avoid: 0.3, attract_red: 0.7}"),
            ),
            ERROR,
        ),
    }


def tables() -> Iterator[Case]:
    heavy = {"deep-yaml", "anchor-bomb", "big-file", "nested-deep"}
    for name, (text, codes) in _tables().items():
        exe = ("execute", "t.yaml", "--world", "corridor", "--max-time", "1", "-o", "r.mcap")
        yield Case(
            name,
            "table",
            exe,
            {"t.yaml": text},
            codes,
            process=name in heavy,
            mem_mb=2500 if name in heavy else None,
        )
        if name in ("valid", "weight-negative", "bac-huge", "anchor-bomb", "deep-yaml", "behaviors-unknown"):
            sim = (
                "simulate",
                "--world",
                "corridor",
                "--teacher",
                "t.yaml",
                "--duration",
                "1",
                "-o",
                "o.mcap",
            )
            yield Case(
                f"{name}-teacher",
                "table",
                sim,
                {"t.yaml": text},
                codes,
                process=name in heavy,
                mem_mb=2500 if name in heavy else None,
            )
        if name in ("valid", "weight-nan", "not-utf8"):
            yield Case(f"{name}-inspect", "table", ("inspect", "t.yaml"), {"t.yaml": text}, OK_OR_ERROR)


# --- task files ------------------------------------------------------------------------------


def tasks() -> Iterator[Case]:
    variants: dict[str, tuple[bytes | str, frozenset[int]]] = {
        "valid": ("task:\n  - {target: red, style: keep-center}\n", frozenset({0})),
        "empty": ("", ERROR),
        "list": ("- {target: red, style: keep-left}\n", ERROR),
        "unknown-key": ("task: [{target: red, style: keep-left}]\nspeed: 3\n", ERROR),
        "task-string": ("task: go\n", ERROR),
        "task-empty": ("task: []\n", ERROR),
        "leg-string": ("task: [red]\n", ERROR),
        "leg-unknown-key": ("task: [{target: red, style: keep-left, speed: 2}]\n", ERROR),
        "style-unknown": ("task: [{target: red, style: moonwalk}]\n", ERROR),
        "style-missing": ("task: [{target: red}]\n", ERROR),
        "style-number": ("task: [{target: red, style: 5}]\n", ERROR),
        "target-unknown": ("task: [{target: purple, style: keep-left}]\n", ERROR),
        "target-number": ("task: [{target: 5, style: keep-left}]\n", ERROR),
        "target-list": ("task: [{target: [red], style: keep-left}]\n", ERROR),
        "target-huge": ("task: [{target: " + "r" * 1_000_000 + ", style: keep-left}]\n", ERROR),
        # bounded by the file size (4 MB), not by a count of legs: 10,000 are valid (boundaries.py)
        "legs-many": ("task:\n" + "  - {target: red, style: keep-left}\n" * 120_000, ERROR),
        "no-target-tour": ("task: [{style: keep-right}]\n", frozenset({0})),
        "anchor-bomb": (_BOMB + "\ntask: *i\n", ERROR),
        "deep": ("task: " + "[" * 20_000 + "]" * 20_000 + "\n", ERROR),
        "not-utf8": (b"task: [{target: \xff, style: keep-left}]\n", ERROR),
        "a-world": (_BOX + "start: [1, 1.5, 0]\n", ERROR),
    }
    heavy = {"anchor-bomb", "deep", "legs-many", "target-huge"}
    for name, (text, codes) in variants.items():
        argv = ("simulate", "--world", "w.yaml", "--teacher", "task.yaml", "--duration", "2", "-o", "o.mcap")
        files: dict[str, Content] = {"task.yaml": text, "w.yaml": lambda b: b["world.yaml"]}
        yield Case(
            name, "task", argv, files, codes, process=name in heavy, mem_mb=2500 if name in heavy else None
        )


# --- paths -----------------------------------------------------------------------------------

Content = bytes | str | Callable[[Base], bytes]


def _ro(d: Path) -> None:
    (d / "ro").mkdir()
    os.chmod(d / "ro", 0o555)


def paths() -> Iterator[Case]:
    demo = {"d.mcap": lambda b: b["demo.mcap"]}
    segd = {"s.mcap": lambda b: b["seg.mcap"]}
    table = {"t.yaml": lambda b: b["table.yaml"]}
    world = {"w.yaml": lambda b: b["world.yaml"]}
    ro = OK_OR_ERROR if AS_ROOT else ERROR
    for cmdname, argv in (
        ("segment", ("segment", "IN")),
        ("estimate", ("estimate", "IN", "-o", "t.yaml")),
        ("inspect", ("inspect", "IN")),
        ("execute", ("execute", "IN", "--max-time", "1", "-o", "r.mcap")),
    ):
        for kind, files, setup in (
            ("dir", {}, lambda d: (d / "IN").mkdir()),
            ("missing", {}, None),
            ("empty", {"IN": b""}, None),
            ("text", {"IN": "hello\n"}, None),
            ("png", {"IN": b"\x89PNG\r\n\x1a\n" + bytes(64)}, None),
            ("magic-only", {"IN": b"\x89MCAP0\r\n"}, None),
            ("zip", {"IN": b"PK\x03\x04" + bytes(100)}, None),
        ):
            yield Case(f"{cmdname}-{kind}", "paths", argv, files, ERROR, setup=setup)
        yield Case(
            f"{cmdname}-fifo",
            "paths",
            argv,
            {},
            ERROR,
            process=True,
            setup=lambda d: os.mkfifo(d / "IN"),
            timeout_s=30,
        )
        yield Case(
            f"{cmdname}-devnull", "paths", tuple("/dev/null" if a == "IN" else a for a in argv), {}, ERROR
        )
    same = [
        ("segment-self", ("segment", "d.mcap", "-o", "d.mcap"), demo),
        ("segment-self-dot", ("segment", "d.mcap", "-o", "./sub/../d.mcap"), {**demo, "sub/x": b""}),
        ("segment-self-link", ("segment", "d.mcap", "-o", "l.mcap"), demo),
        ("estimate-self", ("estimate", "s.mcap", "-o", "s.mcap"), segd),
        (
            "execute-self",
            ("execute", "t.yaml", "--max-time", "1", "--world", "corridor", "-o", "t.yaml"),
            table,
        ),
        (
            "execute-report-self",
            ("execute", "t.yaml", "--max-time", "1", "--world", "corridor", "--report", "t.yaml"),
            table,
        ),
        (
            "execute-report-is-log",
            (
                "execute",
                "t.yaml",
                "--max-time",
                "1",
                "--world",
                "corridor",
                "-o",
                "r.mcap",
                "--report",
                "r.mcap",
            ),
            table,
        ),
        (
            "execute-over-world",
            ("execute", "t.yaml", "--max-time", "1", "--world", "w.yaml", "-o", "w.yaml"),
            {**table, **world},
        ),
        (
            "simulate-over-teacher",
            ("simulate", "--teacher", "t.yaml", "--duration", "1", "--world", "corridor", "-o", "t.yaml"),
            table,
        ),
        ("simulate-over-world", ("simulate", "--world", "w.yaml", "--duration", "1", "-o", "w.yaml"), world),
    ]
    for name, argv, files in same:
        setup = (lambda d: os.symlink("d.mcap", d / "l.mcap")) if name == "segment-self-link" else None
        yield Case(name, "paths", argv, files, ERROR, setup=setup)
    outs = [
        ("segment", ("segment", "d.mcap", "-o", "OUT"), demo, "x.mcap"),
        ("estimate", ("estimate", "s.mcap", "-o", "OUT"), segd, "t.yaml"),
        (
            "execute",
            ("execute", "t.yaml", "--max-time", "1", "--world", "corridor", "-o", "OUT"),
            table,
            "r.mcap",
        ),
        (
            "execute-report",
            (
                "execute",
                "t.yaml",
                "--max-time",
                "1",
                "--world",
                "corridor",
                "-o",
                "r.mcap",
                "--report",
                "OUT",
            ),
            table,
            "r.json",
        ),
        ("simulate", ("simulate", "--world", "corridor", "--duration", "1", "-o", "OUT"), {}, "o.mcap"),
    ]
    for name, argv, files, leaf in outs:
        for kind, path, setup, codes in (
            ("missing-folder", f"nope/{leaf}", None, ERROR),
            ("read-only", f"ro/{leaf}", _ro, ro),
            ("is-dir", "sub", lambda d: (d / "sub").mkdir(), ERROR),
            ("long-name", "n" * 300 + leaf, None, ERROR),
            ("in-file", f"d.mcap/{leaf}", None, ERROR),
        ):
            fl = dict(files)
            if kind == "in-file":
                fl.setdefault("d.mcap", lambda b: b["demo.mcap"])
            yield Case(
                f"{name}-{kind}",
                "paths",
                tuple(path if a == "OUT" else a for a in argv),
                fl,
                codes,
                setup=setup,
            )
    yield Case("estimate-not-segmented", "paths", ("estimate", "d.mcap", "-o", "t.yaml"), demo, ERROR)
    yield Case("execute-an-mcap", "paths", ("execute", "d.mcap", "--max-time", "1"), demo, ERROR)
    yield Case("segment-a-yaml", "paths", ("segment", "t.yaml"), table, ERROR)
    yield Case("segment-twice", "paths", ("segment", "s.mcap", "-o", "s2.mcap"), segd, frozenset({0}))
    yield Case("inspect-world", "paths", ("inspect", "w.yaml"), world, OK_OR_ERROR)
    yield Case("inspect-table", "paths", ("inspect", "t.yaml"), table, OK_OR_ERROR)


# --- signals ---------------------------------------------------------------------------------


def signals() -> Iterator[Case]:
    long_sim = ("simulate", "--world", "corridor", "--duration", "3000", "-o", "s.mcap")
    for sig, name in ((signal.SIGTERM, "term"), (signal.SIGINT, "int")):
        for after in (0.0, 1.0):
            yield Case(
                f"simulate-{name}-{after}",
                "signals",
                long_sim,
                {},
                INTERRUPTED,
                process=True,
                signal_after=(sig, after),
                timeout_s=30,
            )
    yield Case(
        "execute-term",
        "signals",
        (
            "execute",
            "t.yaml",
            "--world",
            "corridor",
            "--max-time",
            "3000",
            "-o",
            "r.mcap",
            "--report",
            "r.json",
        ),
        {"t.yaml": lambda b: b["table.yaml"]},
        INTERRUPTED,
        process=True,
        signal_after=(signal.SIGTERM, 0.5),
        timeout_s=30,
    )
    yield Case(
        "segment-term",
        "signals",
        ("segment", "d.mcap", "-o", "s.mcap"),
        {"d.mcap": lambda b: b["demo.mcap"]},
        INTERRUPTED | {0},
        process=True,
        signal_after=(signal.SIGTERM, 0.0),
        timeout_s=30,
    )


CLASSES: dict[str, Callable[[], Iterator[Case]]] = {
    "mcap_corrupt": mcap_corrupt,
    "mcap_schema": mcap_schema,
    "seg_broken": seg_broken,
    "world": worlds,
    "cli": cli_values,
    "table": tables,
    "task": tasks,
    "paths": paths,
    "signals": signals,
    "boundaries": boundaries,
}


def corpus() -> list[Case]:
    return [case for make in CLASSES.values() for case in make()]


def sample(every: int = 4) -> list[Case]:
    """Every ``every``-th in-process case of each class, plus a few process cases per class."""
    out: list[Case] = []
    for make in CLASSES.values():
        cases = list(make())
        inproc = [c for c in cases if not c.process]
        proc = [c for c in cases if c.process]
        out += inproc[::every] + proc[::3]
    return out
