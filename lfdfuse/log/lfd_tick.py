"""The JSON objects of the ``/lfd/*`` messages an execute run writes every tick (DESIGN §5).

The codecs of :mod:`lfdfuse.log.lfd` make their ``to_dict`` here, and the execute recorder
encodes from the same objects without making a codec first (Python lists, weights rounded once
per row): one layout, so the bytes are the codecs' bytes.
"""

from __future__ import annotations

from collections.abc import Sequence
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


def rounded_weights(weights: dict[str, float]) -> dict[str, float]:
    """The weights as ``/lfd/fused`` carries them: rounded to 1e-4."""
    return {k: round(v, 4) for k, v in weights.items()}


def fused_dict(t_ns: int, x: float, y: float, weights: dict[str, float]) -> dict[str, Any]:
    return {"timestamp": stamp(t_ns), "x": x, "y": y, "weights": rounded_weights(weights)}


def encode_fused_rounded(t_ns: int, x: float, y: float, rounded: dict[str, float]) -> bytes:
    """:func:`~lfdfuse.log.lfd.encode_fused` of weights rounded already (:func:`rounded_weights`)."""
    return orjson.dumps({"timestamp": stamp(t_ns), "x": x, "y": y, "weights": rounded})
