"""The ``/lfd/*`` channels (DESIGN §5): what segment and execute add to a log, encode and decode.

Encoders return the JSON bytes written to the MCAP (``orjson``, vectors rounded to 1e-6);
decoders take the parsed JSON dict. Segment and execute both write ``/lfd/behaviors`` and
``/lfd/bac`` through the same encoders.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import orjson

from lfdfuse.log.stamps import stamp

#: channels that ``segment`` adds (a contract)
SEGMENT_TOPICS: dict[str, str] = {
    "/lfd/behaviors": "lfdfuse.BehaviorOutputs",
    "/lfd/demo": "lfdfuse.DemoHeading",
    "/lfd/bac": "lfdfuse.Bac",
    "/lfd/segment": "lfdfuse.GoalSegment",
}

#: channels that ``execute`` adds (a contract)
EXECUTE_TOPICS: dict[str, str] = {
    "/lfd/behaviors": "lfdfuse.BehaviorOutputs",
    "/lfd/bac": "lfdfuse.Bac",
    "/lfd/step": "lfdfuse.NetworkStep",
    "/lfd/fused": "lfdfuse.FusedVector",
    "/lfd/overlay": "foxglove.SceneUpdate",
}


# --- /lfd/behaviors -------------------------------------------------------------------------


@dataclass(frozen=True)
class BehaviorRow:
    """The behaviour outputs of one tick: ``vectors (K, 2)``, ``applicable (K,)``, ``goal_met (K,)``."""

    names: tuple[str, ...]
    vectors: np.ndarray
    applicable: np.ndarray
    goal_met: np.ndarray


def encode_behaviors(
    t_ns: int, names: Sequence[str], vectors: np.ndarray, applicable: np.ndarray, goal_met: np.ndarray
) -> bytes:
    """``vectors (K, 2)`` already rounded by the caller (one ``np.round`` over a whole log is faster)."""
    vec = vectors.tolist()
    app = applicable.tolist()
    goal = goal_met.tolist()
    return orjson.dumps(
        {
            "timestamp": stamp(t_ns),
            "behaviors": [
                {"name": n, "x": vec[j][0], "y": vec[j][1], "applicable": app[j], "goal_met": goal[j]}
                for j, n in enumerate(names)
            ],
        }
    )


def decode_behaviors(msg: dict[str, Any]) -> BehaviorRow:
    rows = msg["behaviors"]
    return BehaviorRow(
        tuple(str(b["name"]) for b in rows),
        np.array([(b["x"], b["y"]) for b in rows], dtype=np.float64).reshape(len(rows), 2),
        np.array([b["applicable"] for b in rows], dtype=bool),
        np.array([b["goal_met"] for b in rows], dtype=bool),
    )


# --- /lfd/demo ------------------------------------------------------------------------------


def encode_demo(t_ns: int, x: float, y: float, informative: bool) -> bytes:
    """The demonstrated unit vector V_r; ``informative`` False when the command carries no heading."""
    return orjson.dumps(
        {
            "timestamp": stamp(t_ns),
            "x": x,
            "y": y,
            "heading_rad": math.atan2(y, x),
            "informative": informative,
        }
    )


def decode_demo(msg: dict[str, Any]) -> tuple[float, float, bool]:
    """``(x, y, informative)``."""
    return float(msg["x"]), float(msg["y"]), bool(msg["informative"])


# --- /lfd/bac -------------------------------------------------------------------------------


def encode_bac(t_ns: int, bac: int, applicable: Sequence[str]) -> bytes:
    return orjson.dumps({"timestamp": stamp(t_ns), "bac": bac, "applicable": list(applicable)})


def decode_bac(msg: dict[str, Any]) -> int:
    return int(msg["bac"])


# --- /lfd/segment ---------------------------------------------------------------------------


def encode_segment(t_ns: int, index: int, goal: str | None, target: str | None) -> bytes:
    return orjson.dumps({"timestamp": stamp(t_ns), "index": index, "goal": goal, "target": target})


def decode_segment(msg: dict[str, Any]) -> tuple[int, str | None]:
    """``(segment index, goal behaviour or None)``."""
    goal = msg["goal"]
    return int(msg["index"]), None if goal is None else str(goal)


# --- /lfd/step and /lfd/fused (execute) -----------------------------------------------------


def encode_step(
    t_ns: int, *, step: str | None, goal: str | None, bac: int, default_weights: bool, achieved: Sequence[str]
) -> bytes:
    return orjson.dumps(
        {
            "timestamp": stamp(t_ns),
            "step": step,
            "goal": goal,
            "bac": bac,
            "default_weights": default_weights,
            "achieved": list(achieved),
        }
    )


def decode_step(msg: dict[str, Any]) -> tuple[str | None, int, bool]:
    """``(active step or None, bac, default weights used)``."""
    step = msg["step"]
    return None if step is None else str(step), int(msg["bac"]), bool(msg["default_weights"])


def encode_fused(t_ns: int, x: float, y: float, weights: dict[str, float]) -> bytes:
    return orjson.dumps(
        {"timestamp": stamp(t_ns), "x": x, "y": y, "weights": {k: round(v, 4) for k, v in weights.items()}}
    )


def decode_fused(msg: dict[str, Any]) -> tuple[float, float, dict[str, float]]:
    return float(msg["x"]), float(msg["y"]), {str(k): float(v) for k, v in msg["weights"].items()}
