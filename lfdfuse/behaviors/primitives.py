"""Behaviour sets and their outputs (DESIGN §4, the paper's Table I): presets, and :func:`compute`.

:func:`compute` runs the primitives a behaviour set names — each one from the catalogue
(:mod:`lfdfuse.behaviors.catalogue`) — over a block of observations. The same function computes
one scan (live, ``N = 1``) and a whole log (offline); shapes are ``(N, …)`` throughout. A
:class:`BehaviorState` carries what stateful primitives remember from block to block, so a log
computed in blocks, or tick by tick, gives what it gives in one piece.

Magnitudes: every vector has a norm in [0, 1] (a sum of contributions is rescaled into the unit
disc, never clipped per component); each primitive's module says what its length means.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lfdfuse.behaviors.catalogue import BASE_BEHAVIORS, spec_of
from lfdfuse.behaviors.spec import (
    ATTRACT,
    BehaviorParams,
    Observations,
    Primitive,
    Scan,
    distinct_beams,
)
from lfdfuse.errors import ConfigError

__all__ = [
    "ATTRACT",
    "BASE_BEHAVIORS",
    "DEFAULT_PRESET",
    "PRESETS",
    "BehaviorOutputs",
    "BehaviorParams",
    "BehaviorState",
    "Observations",
    "compute",
    "distinct_beams",
    "resolve_behaviors",
]

#: Presets (a contract). ``attract`` expands to one ``attract_<target>`` per target.
PRESETS: dict[str, tuple[str, ...]] = {
    "scenario1": ("avoid", "attract", "wander", "wall_attract", "sonar_avoid"),
    "scenario2": ("avoid", "attract", "wander", "wall_attract_left", "wall_attract_right", "sonar_avoid"),
    "scenario3": (
        "avoid",
        "attract",
        "wander_left",
        "wander_right",
        "wall_attract_left",
        "wall_attract_right",
        "sonar_avoid",
    ),
    # Table I and its variants (DESIGN §4); primitives beyond it are asked for by name
    "full": (
        "avoid",
        "attract",
        "wander",
        "wander_left",
        "wander_right",
        "wall_attract",
        "wall_attract_left",
        "wall_attract_right",
        "sonar_avoid",
        "wall_side_left",
        "wall_side_right",
        "circular_avoid_left",
        "circular_avoid_right",
    ),
}
DEFAULT_PRESET = "scenario3"


def resolve_behaviors(spec: str, targets: Sequence[str]) -> list[str]:
    """A preset or comma list into the ordered behaviour set (``attract`` expanded)."""
    spec = spec.strip()
    items = list(PRESETS[spec]) if spec in PRESETS else [s.strip() for s in spec.split(",") if s.strip()]
    if not items:
        raise ConfigError(f"empty behaviour set (presets: {', '.join(PRESETS)})")
    valid = [*BASE_BEHAVIORS, "attract", *(ATTRACT + t for t in targets)]
    out: list[str] = []
    for name in items:
        if name == "attract":
            out.extend(ATTRACT + t for t in targets)
        elif name in valid:
            out.append(name)
        else:
            raise ConfigError(
                f"unknown behaviour {name!r} (valid: {', '.join(valid)}; presets: {', '.join(PRESETS)})"
            )
    if len(set(out)) != len(out):
        raise ConfigError(f"behaviour set names a behaviour twice: {', '.join(out)}")
    if len(out) > 62:
        raise ConfigError("at most 62 behaviours fit in a BAC bit mask")
    return out


@dataclass(frozen=True)
class BehaviorOutputs:
    """Outputs of a behaviour set for ``N`` instants: ``vectors (N, K, 2)``, ``applicable (N, K)``,
    ``goal_met (N, K)`` (False for behaviours without a goal)."""

    names: tuple[str, ...]
    vectors: np.ndarray
    applicable: np.ndarray
    goal_met: np.ndarray

    @property
    def bac(self) -> np.ndarray:
        """The BAC bit mask ``(N,)`` int64: bit i set ⇔ ``names[i]`` applicable."""
        bits = np.left_shift(np.int64(1), np.arange(len(self.names), dtype=np.int64))
        return np.asarray((self.applicable.astype(np.int64) * bits).sum(axis=1))


class BehaviorState:
    """The primitives of one behaviour set, with what they carry from scan to scan.

    One per log or live run: pass it to every :func:`compute` of that log's blocks (or ticks) in
    time order; :meth:`reset` starts over.
    """

    def __init__(self, names: Sequence[str], params: BehaviorParams = BehaviorParams()) -> None:
        self.names = tuple(names)
        self.params = params
        self.primitives: list[Primitive] = []
        for name in self.names:
            s = spec_of(name)
            if s is None:
                raise ConfigError(f"unknown behaviour {name!r}")
            self.primitives.append(s.make(name, params))

    def reset(self) -> None:
        for p in self.primitives:
            p.reset()


def compute(
    obs: Observations,
    names: Sequence[str],
    params: BehaviorParams = BehaviorParams(),
    state: BehaviorState | None = None,
) -> BehaviorOutputs:
    """Outputs of the behaviours ``names`` on ``obs``.

    ``state`` carries stateful primitives from the previous block (its names and parameters must
    be these); None: ``obs`` is the start of a log.
    """
    if state is None:
        state = BehaviorState(names, params)
    elif state.names != tuple(names) or state.params != params:
        raise ConfigError("the behaviour state was made for another behaviour set or other parameters")
    scan = Scan(obs, params)
    n, k = scan.n, len(state.names)
    vec = np.zeros((n, k, 2))
    app = np.zeros((n, k), dtype=bool)
    goal = np.zeros((n, k), dtype=bool)
    for i, primitive in enumerate(state.primitives):
        res = primitive.step(scan)
        a = res.applicable
        vec[:, i] = np.where(a[:, None], res.vector, 0.0)
        app[:, i] = a
        if res.goal is not None:
            goal[:, i] = res.goal
    return BehaviorOutputs(state.names, vec, app, goal)
