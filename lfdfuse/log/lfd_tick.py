"""The JSON objects of the ``/lfd/*`` messages an execute run writes every tick (DESIGN §5).

The codecs of :mod:`lfdfuse.log.lfd` make their ``to_dict`` here, and the execute recorder
encodes from the same objects without making a codec first (Python lists, weights rounded once
per row): one layout, so the bytes are the codecs' bytes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import orjson

from lfdfuse.log.stamps import stamp


def behaviors_dict(
    t_ns: int, names: Sequence[str], xy: list[list[float]], applicable: list[bool], goal_met: list[bool]
) -> dict[str, Any]:
    """:meth:`~lfdfuse.log.lfd.BehaviorRow.to_dict` of its fields as Python lists (``ndarray.tolist()``)."""
    return {
        "timestamp": stamp(t_ns),
        "behaviors": [
            {"name": n, "x": xy[j][0], "y": xy[j][1], "applicable": applicable[j], "goal_met": goal_met[j]}
            for j, n in enumerate(names)
        ],
    }


def encode_behavior_lists(
    t_ns: int, names: Sequence[str], xy: list[list[float]], applicable: list[bool], goal_met: list[bool]
) -> bytes:
    """:func:`~lfdfuse.log.lfd.encode_behaviors` of the arrays as Python lists (a caller that has them already)."""
    return orjson.dumps(behaviors_dict(t_ns, names, xy, applicable, goal_met))


def bac_dict(t_ns: int, bac: int, applicable: Sequence[str]) -> dict[str, Any]:
    return {"timestamp": stamp(t_ns), "bac": bac, "applicable": list(applicable)}


def step_dict(
    t_ns: int, step: str | None, goal: str | None, bac: int, default_weights: bool, achieved: Sequence[str]
) -> dict[str, Any]:
    return {
        "timestamp": stamp(t_ns),
        "step": step,
        "goal": goal,
        "bac": bac,
        "default_weights": default_weights,
        "achieved": list(achieved),
    }


def rounded_weights(weights: Mapping[str, float]) -> dict[str, float]:
    """The weights as ``/lfd/fused`` carries them: rounded to 1e-4."""
    return {k: round(v, 4) for k, v in weights.items()}


def fused_dict(t_ns: int, x: float, y: float, weights: dict[str, float]) -> dict[str, Any]:
    return {"timestamp": stamp(t_ns), "x": x, "y": y, "weights": rounded_weights(weights)}


def encode_fused_rounded(t_ns: int, x: float, y: float, rounded: dict[str, float]) -> bytes:
    """:func:`~lfdfuse.log.lfd.encode_fused` of weights rounded already (:func:`rounded_weights`)."""
    return orjson.dumps({"timestamp": stamp(t_ns), "x": x, "y": y, "weights": rounded})


# --- the same bytes, spliced: what a run writes every tick, without a dict per field ----------
#
# orjson writes compact JSON (no spaces) and a number the same wherever it stands, so a message
# is its fixed pieces (made once, by orjson) around the numbers of this tick, each as orjson
# writes it in one list. The tests hold these against the dict encoders above.


def stamp_head(t_ns: int) -> bytes:
    """``{"timestamp":{...}`` as every message above begins (the integers as orjson writes them)."""
    return b'{"timestamp":{"sec":%d,"nsec":%d}' % (t_ns // 1_000_000_000, t_ns % 1_000_000_000)


def numbers(values: list[float]) -> list[bytes]:
    """Each number of a flat list as orjson writes it (NaN and ±inf as ``null``)."""
    return orjson.dumps(values)[1:-1].split(b",") if values else []


class BehaviorsEncoder:
    """:func:`encode_behavior_lists` for one behaviour set (the same bytes): the message as a
    bytes format per pattern of applicability and goals met, made once (by orjson, of the
    message with marked numbers) and filled in with this tick's numbers."""

    def __init__(self, names: Sequence[str]) -> None:
        self.names = tuple(names)
        self._formats: dict[tuple[bool, ...], bytes] = {}

    def _format(self, applicable: list[bool], goal_met: list[bool]) -> bytes:
        k = len(self.names)
        marks = [100_000.5 + i for i in range(2 * k)]  # each written once, after its key
        xy = [marks[2 * j : 2 * j + 2] for j in range(k)]
        data = orjson.dumps(behaviors_dict(0, self.names, xy, applicable, goal_met)).replace(b"%", b"%%")
        head = orjson.dumps({"timestamp": stamp(0)})[1:-1]
        assert data.startswith(b"{" + head)
        data = b'{"timestamp":{"sec":%d,"nsec":%d}' + data[1 + len(head) :]
        for i, mark in enumerate(marks):
            key = b'"x":' if i % 2 == 0 else b'"y":'
            data = data.replace(key + orjson.dumps(mark) + b",", key + b"%s,", 1)
        return data

    def encode(self, t_ns: int, xy: list[list[float]], applicable: list[bool], goal_met: list[bool]) -> bytes:
        """``applicable`` and ``goal_met`` as Python bools (a bool array's ``tolist()``)."""
        k = len(self.names)
        if len(xy) != k or len(applicable) != k or len(goal_met) != k:
            return encode_behavior_lists(t_ns, self.names, xy, applicable, goal_met)
        flat = orjson.dumps(xy).replace(b"[", b"").replace(b"]", b"").split(b",") if k else []
        if len(flat) != 2 * k:  # not (K, 2)
            return encode_behavior_lists(t_ns, self.names, xy, applicable, goal_met)
        return self._filled(t_ns, flat, applicable, goal_met)

    def encode_flat(self, t_ns: int, xy: list[float], applicable: list[bool], goal_met: list[bool]) -> bytes:
        """:meth:`encode` of the vectors as one flat list ``x0, y0, x1, y1, …`` (a ``(K, 2)``
        array's ``ravel().tolist()``): the same bytes, one nesting less to write and undo."""
        k = len(self.names)
        if len(xy) != 2 * k or len(applicable) != k or len(goal_met) != k:
            return encode_behavior_lists(
                t_ns, self.names, [xy[i : i + 2] for i in range(0, len(xy), 2)], applicable, goal_met
            )
        return self._filled(t_ns, orjson.dumps(xy)[1:-1].split(b",") if k else [], applicable, goal_met)

    def _filled(self, t_ns: int, flat: list[bytes], applicable: list[bool], goal_met: list[bool]) -> bytes:
        """The message of this pattern's format, filled with the numbers as orjson writes them."""
        key = (*applicable, *goal_met)
        fmt = self._formats.get(key)
        if fmt is None:
            if len(self._formats) >= 4096:
                self._formats.clear()
            fmt = self._formats[key] = self._format(applicable, goal_met)
        return fmt % (t_ns // 1_000_000_000, t_ns % 1_000_000_000, *flat)


def tail_of(message: dict[str, Any]) -> bytes:
    """The bytes of ``message`` (whose first field is its ``timestamp``) after the timestamp:
    what follows :func:`stamp_head` in its message (``,...}``)."""
    data = orjson.dumps(message)
    head = len(orjson.dumps({"timestamp": message["timestamp"]})) - 1
    assert data.startswith(b'{"timestamp":'), data[:40]
    return data[head:]
