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

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lfdfuse.behaviors import kernels
from lfdfuse.behaviors.catalogue import BASE_BEHAVIORS, spec_of
from lfdfuse.behaviors.library.attract import Attract
from lfdfuse.behaviors.spec import (
    ATTRACT,
    BehaviorParams,
    Observations,
    Primitive,
    Scan,
    distinct_beams,
    sees_none,
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
        if self.applicable.shape[0] == 1:  # a live tick: the same bits without the array work
            mask = sum(1 << j for j, a in enumerate(self.applicable[0].tolist()) if a)
            return np.array([mask], dtype=np.int64)
        bits = np.left_shift(np.int64(1), np.arange(len(self.names), dtype=np.int64))
        return np.asarray((self.applicable.astype(np.int64) * bits).sum(axis=1))


def made_outputs(
    names: tuple[str, ...], vectors: np.ndarray, applicable: np.ndarray, goal_met: np.ndarray
) -> BehaviorOutputs:
    """``BehaviorOutputs(...)``, the same instance, without the frozen ``__init__``'s
    ``object.__setattr__`` per field (a live run makes one every tick)."""
    o = object.__new__(BehaviorOutputs)
    o.__dict__.update(names=names, vectors=vectors, applicable=applicable, goal_met=goal_met)
    return o


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
        #: the fused plan of the last block (see :func:`_fused`) and what it was made for
        self.plan: tuple[BehaviorParams, object, tuple[str, ...], np.ndarray | None, _Plan] | None = None
        #: the columns the fused loop did, and the primitives left to step (in order)
        self.rest: tuple[frozenset[int], list[tuple[int, Primitive]]] | None = None

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
    elif (state.names is not names and state.names != tuple(names)) or (
        state.params is not params and state.params != params
    ):
        raise ConfigError("the behaviour state was made for another behaviour set or other parameters")
    scan = Scan(obs, params)
    n, k = scan.n, len(state.names)
    vec = np.zeros((n, k, 2))
    app = np.zeros((n, k), dtype=bool)
    goal = np.zeros((n, k), dtype=bool)
    done = _fused(scan, state, vec, app, goal) if kernels.POOL.ready() else frozenset()
    rest = state.rest
    if rest is None or rest[0] is not done:  # the primitives left to step, once per plan
        rest = state.rest = (done, [(i, p) for i, p in enumerate(state.primitives) if i not in done])
    for i, primitive in rest[1]:
        res = primitive.step(scan)
        a = res.applicable
        vec[:, i] = np.where(a[:, None], res.vector, 0.0)
        app[:, i] = a
        if res.goal is not None:
            goal[:, i] = res.goal
    return made_outputs(state.names, vec, app, goal)


_KINDS = {
    "avoid": kernels.AVOID,
    "wander": kernels.WANDER,
    "wall_attract": kernels.WALL_ATTRACT,
    "wall_side": kernels.WALL_SIDE,
    "sonar_avoid": kernels.SONAR_AVOID,
}


@dataclass(frozen=True)
class _Plan:
    """What :func:`_fused` computes of a behaviour set on one scanner layout, sonar layout and
    target list: the compiled loop's ops ``(M, 3)`` (kind, sector, column), ``sectors (3, B)``
    (front, left, right), ``dirs (M, max(B, S), 2)`` (each op's directions as its numpy
    primitive pools them), the ``attract_<target>`` columns and their targets' indices."""

    sonar_angles: np.ndarray | None
    ops: np.ndarray
    sectors: np.ndarray
    dirs: np.ndarray
    attract_cols: list[int]
    attract_targets: list[int]
    done: frozenset[int]
    own: np.ndarray  # the layout's own beams (``Scan.own``)


def _plan(scan: Scan, state: BehaviorState, sonar: bool) -> _Plan:
    obs, beams = scan.obs, scan.beams
    sonar_dirs = None
    if sonar and obs.sonar_angles_rad is not None:
        a = obs.sonar_angles_rad
        sonar_dirs = -np.column_stack([np.cos(a), np.sin(a)])
    size = max(len(beams.ang), 0 if sonar_dirs is None else len(sonar_dirs))
    ops: list[tuple[int, int, int]] = []
    dirs: list[np.ndarray] = []
    cols: list[int] = []
    targets: list[int] = []
    for col, p in enumerate(state.primitives):
        if isinstance(p, Attract):
            if p.target in obs.target_names:
                cols.append(col)
                targets.append(obs.target_names.index(p.target))
            continue
        fused = getattr(p, "fused", None)
        if fused is None:
            continue
        kind, sector, turn = fused
        if kind == "sonar_avoid":
            if sonar_dirs is None:
                continue  # never applicable: the primitive's own zeros
            d = sonar_dirs
        elif kind == "avoid":
            d = beams.away
        elif kind == "wall_side":
            d = beams.tangent(turn)
        else:
            d = beams.dirs
        block = np.zeros((size, 2))
        block[: len(d)] = d
        ops.append((_KINDS[kind], ("front", "left", "right").index(sector) if sector else 0, col))
        dirs.append(block)
    return _Plan(
        obs.sonar_angles_rad if sonar else None,
        np.asarray(ops, dtype=np.int64).reshape(-1, 3),
        np.stack([beams.front, beams.left, beams.right]),
        np.asarray(dirs, dtype=np.float64).reshape(-1, size, 2),
        cols,
        targets,
        frozenset([c for _, _, c in ops] + cols),
        scan.own,
    )


_NO_SONAR = np.zeros((1, 0))

#: the plans of the behaviour sets computed lately, per set, parameters, layout, targets and
#: sonars (the sonar angles by identity, checked against the plan's own)
_PLANS: dict[tuple[object, ...], _Plan] = {}


def _fused(
    scan: Scan, state: BehaviorState, vec: np.ndarray, app: np.ndarray, goal: np.ndarray
) -> frozenset[int]:
    """Compute the primitives that have a fused loop (:data:`~lfdfuse.behaviors.kernels.POOL`)
    and the ``attract_<target>`` ones (all targets at once) into ``vec``, ``app``, ``goal``: the
    same numbers as their own :meth:`~lfdfuse.behaviors.spec.Primitive.step`. The columns done."""
    obs, params = scan.obs, scan.params
    sonar = obs.sonar_m if obs.sonar_angles_rad is not None else None
    if scan.r.dtype != np.float64 or (sonar is not None and sonar.dtype != np.float64):
        return frozenset()
    # the plan of the state's last block, when this block has the same layout, targets and
    # sonars (the same objects: a live run's every tick); else looked up by value
    last = state.plan
    if (
        last is not None
        and last[0] is params
        and last[1] is obs.geometry
        and last[2] is obs.target_names
        and last[3] is (obs.sonar_angles_rad if sonar is not None else None)
    ):
        plan = last[4]
    else:
        key = (
            state.names,
            params,
            obs.geometry,
            obs.target_names,
            id(obs.sonar_angles_rad) if sonar is not None else 0,
        )
        known = _PLANS.get(key)
        if known is None or (sonar is not None and known.sonar_angles is not obs.sonar_angles_rad):
            if len(_PLANS) >= 64:
                _PLANS.clear()
            known = _PLANS[key] = _plan(scan, state, sonar is not None)
        plan = known
        state.plan = (
            params,
            obs.geometry,
            obs.target_names,
            obs.sonar_angles_rad if sonar is not None else None,
            plan,
        )
    if len(plan.ops):
        thr = params.sonar_threshold_m
        kernels.POOL(
            np.ascontiguousarray(scan.r),
            plan.own,
            obs.geometry.max_range_m,
            params.d_max_m,
            _NO_SONAR if sonar is None else np.ascontiguousarray(sonar),
            min(thr, obs.sonar_max_m),
            thr,
            plan.ops,
            plan.sectors,
            plan.dirs,
            vec,
            app,
        )
    cols = plan.attract_cols
    if cols and sees_none(obs):
        pass  # a live tick that sees no target: every attract column stays zero, as below
    elif cols and scan.n == 1:
        # one scan (a live tick): the targets seen, one by one, the same numbers (numpy's sine
        # and cosine of each bearing); a target not seen leaves its column zero, as below
        bearing, rng = obs.target_bearing_rad[0].tolist(), obs.target_range_m[0].tolist()
        for col, j in zip(cols, plan.attract_targets, strict=True):
            b, tr = bearing[j], rng[j]
            if math.isfinite(b) and math.isfinite(tr):
                vec[0, col, 0] = np.cos(b)
                vec[0, col, 1] = np.sin(b)
                app[0, col] = True
                goal[0, col] = tr <= params.reach_m
    elif cols:
        js = plan.attract_targets
        b, tr = obs.target_bearing_rad[:, js], obs.target_range_m[:, js]
        a = np.isfinite(b) & np.isfinite(tr)
        bb = np.where(a, b, 0.0)
        vec[:, cols, 0] = np.where(a, np.cos(bb), 0.0)
        vec[:, cols, 1] = np.where(a, np.sin(bb), 0.0)
        app[:, cols] = a
        goal[:, cols] = a & (np.where(a, tr, np.inf) <= params.reach_m)
    return plan.done
