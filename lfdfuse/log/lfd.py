"""The ``/lfd/*`` channels (DESIGN §5): what segment and execute add to a log, encode and decode.

Each channel is a frozen dataclass with its ``TOPIC`` and ``SCHEMA`` beside ``to_dict`` /
``encode`` (the JSON bytes written to the MCAP, ``orjson``; behaviour vectors rounded to 1e-6
by the caller) and ``from_dict`` / ``decode``. The decoders are the only readers of these
channels: they check what the schema in ``schemas/`` states (required fields, no others, the
JSON types, integers that are not booleans, non-negative stamps, bitmasks and indices, finite
numbers) once, with the checks of :mod:`lfdfuse.log.codec`, and raise its
:class:`~lfdfuse.log.codec.MessageError` otherwise; a reader names the file, the
channel and the time. What a schema cannot state (a known behaviour name, a BAC that agrees with
the applicability bits) is for the reader to check.

Segment and execute both write ``/lfd/behaviors`` and ``/lfd/bac`` through the same encoders.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Literal, get_args

import numpy as np
import orjson

from lfdfuse.log.codec import (
    Codec,
    MessageError,
    as_choice,
    as_count,
    as_flag,
    as_name,
    as_name_or_none,
    as_names,
    as_number,
    check_fields,
    keys_error,
    timestamp_ns,
)
from lfdfuse.log.command import DriveCommand
from lfdfuse.log.lfd_tick import bac_dict, behaviors_dict, encode_behavior_lists, fused_dict, step_dict
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
    "/lfd/network": "lfdfuse.NetworkEvent",
}

#: channels that ``teleop --table`` adds beside execute's (a contract; ``drive`` may write it too)
CORRECTION_TOPICS: dict[str, str] = {
    "/lfd/authority": "lfdfuse.Authority",
}


# --- /lfd/behaviors -------------------------------------------------------------------------

_BEHAVIOR_KEYS = frozenset({"name", "x", "y", "applicable", "goal_met"})
_ROW_FIELDS = operator.itemgetter("name", "x", "y", "applicable", "goal_met")
_NO_ROWS: tuple[tuple[Any, ...], ...] = ((), (), (), (), ())
_STR, _REAL, _BOOL = frozenset({str}), frozenset({int, float}), frozenset({bool})


def _check_behavior(b: object) -> None:
    """The precise error for a behaviour entry the fast path refused."""
    if type(b) is not dict:
        raise MessageError("a behaviour is not an object")
    if b.keys() != _BEHAVIOR_KEYS:
        raise keys_error(b, _BEHAVIOR_KEYS)
    name = as_name(b["name"], "a behaviour name")
    as_number(b["x"], f"x of {name!r:.40}")
    as_number(b["y"], f"y of {name!r:.40}")
    as_flag(b["applicable"], f"applicable of {name!r:.40}")
    as_flag(b["goal_met"], f"goal_met of {name!r:.40}")


@dataclass(frozen=True, eq=False)  # arrays: compare the fields
class BehaviorRow(Codec):
    """``lfdfuse.BehaviorOutputs``: the behaviour outputs of one tick.

    ``vectors (K, 2)`` robot-frame (x, y), ``applicable (K,)`` and ``goal_met (K,)`` booleans.
    """

    TOPIC: ClassVar[str] = "/lfd/behaviors"
    SCHEMA: ClassVar[str] = "lfdfuse.BehaviorOutputs"
    KEYS: ClassVar[frozenset[str]] = frozenset({"timestamp", "behaviors"})

    t_ns: int
    names: tuple[str, ...]
    vectors: np.ndarray
    applicable: np.ndarray
    goal_met: np.ndarray

    def to_dict(self) -> dict[str, Any]:
        return behaviors_dict(
            self.t_ns, self.names, self.vectors.tolist(), self.applicable.tolist(), self.goal_met.tolist()
        )

    @classmethod
    def from_dict(cls, msg: dict[str, Any]) -> BehaviorRow:
        row = super().from_dict(msg)
        if not np.isfinite(row.vectors).all():  # orjson refuses NaN and overflow: only other dicts
            raise MessageError("a behaviour vector is not finite")
        return row

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> BehaviorRow:
        check_fields(msg, cls.KEYS)
        t_ns = timestamp_ns(msg)
        rows = msg["behaviors"]
        if type(rows) is not list:
            raise MessageError("behaviors is not a list")
        # the hot loop of reading a log, kept in C: the five fields of every behaviour as
        # columns, each column's set of types against the allowed; the details only on failure
        try:
            names, xs, ys, app, goal = zip(*map(_ROW_FIELDS, rows), strict=True) if rows else _NO_ROWS
        except (TypeError, KeyError):
            names = ()
        if not (
            len(names) == len(rows)
            and set(map(type, names)) <= _STR
            and set(map(type, xs)) | set(map(type, ys)) <= _REAL
            and set(map(type, app)) | set(map(type, goal)) <= _BOOL
            and sum(map(len, rows)) == len(_BEHAVIOR_KEYS) * len(rows)
        ):
            for b in rows:
                _check_behavior(b)
            raise MessageError("a behaviour breaks the schema")  # not reached: the checks name it
        try:
            vectors = np.array((xs, ys), dtype=np.float64).reshape(2, len(rows)).T
        except OverflowError:  # an integer beyond a double, from a parser other than orjson
            raise MessageError("a behaviour vector is too large for a float") from None
        return cls(t_ns, names, vectors, np.array(app, dtype=bool), np.array(goal, dtype=bool))


def encode_behaviors(
    t_ns: int, names: Sequence[str], vectors: np.ndarray, applicable: np.ndarray, goal_met: np.ndarray
) -> bytes:
    """``vectors (K, 2)`` already rounded by the caller (one ``np.round`` over a whole log is faster)."""
    return encode_behavior_lists(t_ns, names, vectors.tolist(), applicable.tolist(), goal_met.tolist())


def decode_behaviors(data: bytes) -> BehaviorRow:
    return BehaviorRow.decode(data)


# --- /lfd/demo ------------------------------------------------------------------------------


@dataclass(frozen=True)
class DemoHeading(Codec):
    """``lfdfuse.DemoHeading``: the demonstrated unit vector V_r (robot frame);
    ``informative`` False when the command carries no heading."""

    TOPIC: ClassVar[str] = "/lfd/demo"
    SCHEMA: ClassVar[str] = "lfdfuse.DemoHeading"
    KEYS: ClassVar[frozenset[str]] = frozenset({"timestamp", "x", "y", "heading_rad", "informative"})

    t_ns: int
    x: float
    y: float
    informative: bool

    @property
    def heading_rad(self) -> float:
        return math.atan2(self.y, self.x)

    def to_dict(self) -> dict[str, Any]:
        return {
            "timestamp": stamp(self.t_ns),
            "x": self.x,
            "y": self.y,
            "heading_rad": self.heading_rad,
            "informative": self.informative,
        }

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> DemoHeading:
        check_fields(msg, cls.KEYS)
        as_number(msg["heading_rad"], "heading_rad")  # derived from x, y: checked, not kept
        return cls(
            timestamp_ns(msg),
            as_number(msg["x"], "x"),
            as_number(msg["y"], "y"),
            as_flag(msg["informative"], "informative"),
        )


def encode_demo(t_ns: int, x: float, y: float, informative: bool) -> bytes:
    """The demonstrated unit vector V_r; ``informative`` False when the command carries no heading."""
    return DemoHeading(t_ns, x, y, informative).encode()


def decode_demo(data: bytes) -> DemoHeading:
    return DemoHeading.decode(data)


# --- /lfd/bac -------------------------------------------------------------------------------


@dataclass(frozen=True)
class Bac(Codec):
    """``lfdfuse.Bac``: the applicability bit mask (bit i: behaviour i applicable) and the names."""

    TOPIC: ClassVar[str] = "/lfd/bac"
    SCHEMA: ClassVar[str] = "lfdfuse.Bac"
    KEYS: ClassVar[frozenset[str]] = frozenset({"timestamp", "bac", "applicable"})

    t_ns: int
    bac: int
    applicable: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        return bac_dict(self.t_ns, self.bac, self.applicable)

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> Bac:
        check_fields(msg, cls.KEYS)
        return cls(timestamp_ns(msg), as_count(msg["bac"], "bac"), as_names(msg["applicable"], "applicable"))


def encode_bac(t_ns: int, bac: int, applicable: Sequence[str]) -> bytes:
    return orjson.dumps(bac_dict(t_ns, bac, applicable))


def decode_bac(data: bytes) -> Bac:
    return Bac.decode(data)


# --- /lfd/segment ---------------------------------------------------------------------------


@dataclass(frozen=True)
class SegmentMark(Codec):
    """``lfdfuse.GoalSegment``: the goal segment a tick belongs to, the behaviour whose goal ends
    it and that goal's target (both None for a trailing part that reaches no goal)."""

    TOPIC: ClassVar[str] = "/lfd/segment"
    SCHEMA: ClassVar[str] = "lfdfuse.GoalSegment"
    KEYS: ClassVar[frozenset[str]] = frozenset({"timestamp", "index", "goal", "target"})

    t_ns: int
    index: int
    goal: str | None
    target: str | None

    def to_dict(self) -> dict[str, Any]:
        return {"timestamp": stamp(self.t_ns), "index": self.index, "goal": self.goal, "target": self.target}

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> SegmentMark:
        check_fields(msg, cls.KEYS)
        return cls(
            timestamp_ns(msg),
            as_count(msg["index"], "index"),
            as_name_or_none(msg["goal"], "goal"),
            as_name_or_none(msg["target"], "target"),
        )


def encode_segment(t_ns: int, index: int, goal: str | None, target: str | None) -> bytes:
    return SegmentMark(t_ns, index, goal, target).encode()


def decode_segment(data: bytes) -> SegmentMark:
    return SegmentMark.decode(data)


# --- /lfd/step and /lfd/fused (execute) -----------------------------------------------------


@dataclass(frozen=True)
class NetworkStep(Codec):
    """``lfdfuse.NetworkStep``: the active step of a tick (nested names joined by ``/``; None when
    the task is complete), its goal, the BAC, whether default weights were used (a BAC never
    seen in training), and the goals achieved so far, in order."""

    TOPIC: ClassVar[str] = "/lfd/step"
    SCHEMA: ClassVar[str] = "lfdfuse.NetworkStep"
    KEYS: ClassVar[frozenset[str]] = frozenset(
        {"timestamp", "step", "goal", "bac", "default_weights", "achieved"}
    )

    t_ns: int
    step: str | None
    goal: str | None
    bac: int
    default_weights: bool
    achieved: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        return step_dict(self.t_ns, self.step, self.goal, self.bac, self.default_weights, self.achieved)

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> NetworkStep:
        check_fields(msg, cls.KEYS)
        return cls(
            timestamp_ns(msg),
            as_name_or_none(msg["step"], "step"),
            as_name_or_none(msg["goal"], "goal"),
            as_count(msg["bac"], "bac"),
            as_flag(msg["default_weights"], "default_weights"),
            as_names(msg["achieved"], "achieved"),
        )


def encode_step(
    t_ns: int, *, step: str | None, goal: str | None, bac: int, default_weights: bool, achieved: Sequence[str]
) -> bytes:
    return orjson.dumps(step_dict(t_ns, step, goal, bac, default_weights, achieved))


@dataclass(frozen=True)
class FusedVector(Codec):
    """``lfdfuse.FusedVector``: the fused robot-frame vector and the weights that made it
    (rounded to 1e-4 on the wire, so a decoded message holds the rounded weights)."""

    TOPIC: ClassVar[str] = "/lfd/fused"
    SCHEMA: ClassVar[str] = "lfdfuse.FusedVector"
    KEYS: ClassVar[frozenset[str]] = frozenset({"timestamp", "x", "y", "weights"})

    t_ns: int
    x: float
    y: float
    weights: dict[str, float]

    def to_dict(self) -> dict[str, Any]:
        return fused_dict(self.t_ns, self.x, self.y, self.weights)

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> FusedVector:
        check_fields(msg, cls.KEYS)
        w = msg["weights"]
        if type(w) is not dict:
            raise MessageError("weights is not an object")
        weights = {k: as_number(v, f"the weight of {k!r:.40}") for k, v in w.items()}
        if any(v < 0 for v in weights.values()):
            raise MessageError("a weight is negative")
        return cls(timestamp_ns(msg), as_number(msg["x"], "x"), as_number(msg["y"], "y"), weights)


def encode_fused(t_ns: int, x: float, y: float, weights: dict[str, float]) -> bytes:
    return orjson.dumps(fused_dict(t_ns, x, y, weights))


def decode_fused(data: bytes) -> FusedVector:
    return FusedVector.decode(data)


# --- /lfd/network (execute, teleop --table) --------------------------------------------------

#: why the network asks for help: the BAC has no row in the active step, or its row's weights
#: are not identifiable from the demonstration (the prior decides them)
HelpReason = Literal["unseen BAC", "not identifiable"]
HELP_REASONS: tuple[HelpReason, ...] = get_args(HelpReason)
NETWORK_EVENTS = ("help",)


@dataclass(frozen=True)
class NetworkEvent(Codec):
    """``lfdfuse.NetworkEvent``: something the network says about itself at one tick; for now only
    ``help``: it entered a BAC of ``step`` that its table cannot drive with confidence (``why``).

    Written once when the condition begins (not every tick while it lasts), so a log reader sees
    each request for help once. A channel of its own, not a field of ``/lfd/step``: that schema
    forbids extra fields, so old readers keep reading new logs.
    """

    TOPIC: ClassVar[str] = "/lfd/network"
    SCHEMA: ClassVar[str] = "lfdfuse.NetworkEvent"
    KEYS: ClassVar[frozenset[str]] = frozenset({"timestamp", "event", "step", "bac", "why"})

    t_ns: int
    event: str
    step: str
    bac: int
    why: str

    def to_dict(self) -> dict[str, Any]:
        return {
            "timestamp": stamp(self.t_ns),
            "event": self.event,
            "step": self.step,
            "bac": self.bac,
            "why": self.why,
        }

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> NetworkEvent:
        check_fields(msg, cls.KEYS)
        return cls(
            timestamp_ns(msg),
            as_choice(msg["event"], NETWORK_EVENTS, "event"),
            as_name(msg["step"], "step"),
            as_count(msg["bac"], "bac"),
            as_choice(msg["why"], HELP_REASONS, "why"),
        )


def encode_help(t_ns: int, *, step: str, bac: int, why: str) -> bytes:
    return NetworkEvent(t_ns, "help", step, bac, why).encode()


def decode_network_event(data: bytes) -> NetworkEvent:
    return NetworkEvent.decode(data)


# --- /lfd/authority (teleop --table, drive) ---------------------------------------------------

AUTHORITIES = ("network", "person")


@dataclass(frozen=True)
class Authority(Codec):
    """``lfdfuse.Authority``: who drove this tick — ``network`` (a fusion table) or ``person`` —
    and through what (``keyboard``, ``script``, ``foxglove client 3``; empty when unknown).

    One message per tick of a run where both can drive; ``segment`` reads it to tell the
    learner's own ticks from the teacher's.
    """

    TOPIC: ClassVar[str] = "/lfd/authority"
    SCHEMA: ClassVar[str] = "lfdfuse.Authority"
    KEYS: ClassVar[frozenset[str]] = frozenset({"timestamp", "authority", "source"})

    t_ns: int
    authority: str
    source: str = ""

    @property
    def person(self) -> bool:
        """Whether a person drove this tick."""
        return self.authority == "person"

    def to_dict(self) -> dict[str, Any]:
        return {"timestamp": stamp(self.t_ns), "authority": self.authority, "source": self.source}

    @classmethod
    def _from_json(cls, msg: dict[str, Any]) -> Authority:
        check_fields(msg, cls.KEYS)
        return cls(
            timestamp_ns(msg),
            as_choice(msg["authority"], AUTHORITIES, "authority"),
            as_name(msg["source"], "source"),
        )


def encode_authority(t_ns: int, authority: str, source: str = "") -> bytes:
    return Authority(t_ns, authority, source).encode()


def decode_authority(data: bytes) -> Authority:
    return Authority.decode(data)


#: every ``/lfd/*`` message class, by topic (``drive``'s :class:`~lfdfuse.log.command.DriveCommand` too)
CODECS: dict[str, type[Codec]] = {
    c.TOPIC: c
    for c in (BehaviorRow, DemoHeading, Bac, SegmentMark, NetworkStep, FusedVector, NetworkEvent, Authority)
}
CODECS[DriveCommand.TOPIC] = DriveCommand
