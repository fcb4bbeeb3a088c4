"""Behaviour primitives (DESIGN §4, the paper's Table I), computed over arrays.

Every primitive maps observations to a robot-frame vector with norm in [0, 1], a precondition
(applicable now?) and, for ``attract_<target>``, a goal (the target reached). The same function
computes one scan (live, ``N = 1``) and a whole log (offline); shapes are ``(N, …)`` throughout.

A laser beam has *no return* when its range is inf, NaN, ≤ 0, or at/above the scanner's max
range (the sentinel real scanners and our logs use); such beams count as open space. Beams
outside a behaviour's sector are ignored, so any scanner geometry works (180°, 240°, 360°, any
start angle and increment): sectors are chosen by beam bearing, never by beam index, the rear
beams of a 360° scanner belong to ``avoid`` only, and a beam repeating an earlier bearing (a
360° + 1 scanner) is ignored. A log without sonar or camera makes ``sonar_avoid`` and
``attract_*`` never applicable.

Magnitudes (how strongly a primitive pulls; a sum of contributions is rescaled into the unit
disc, never clipped per component):

* ``avoid``, ``sonar_avoid``, ``wall_side_*``: direction of the summed contributions, length of
  the strongest one, ``(d_max − r) / d_max`` — grows as the robot nears the object.
* ``wander*``: the mean of unit vectors over the sector's beams, open beams only — long when
  the open space is wide and straight ahead.
* ``wall_attract*``: toward the returns closer than ``d_max`` (the wall normal), length
  ``r_min / d_max`` — a spring: with ``avoid`` it has an equilibrium distance set by the
  weights, which is how a learned fusion holds a distance to its wall.
* ``circular_avoid_*``: 30° to its side, length ``(d_max − r_min) / d_max`` of the cone.
* ``attract_<target>``: unit vector toward the target.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.robot.readings import Detection, ScanGeometry

BASE_BEHAVIORS = (
    "avoid",
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
)

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
    "full": ("avoid", "attract", *BASE_BEHAVIORS[1:]),
}
DEFAULT_PRESET = "scenario3"
ATTRACT = "attract_"


@dataclass(frozen=True)
class BehaviorParams:
    """Parameters of the primitives (metres, radians)."""

    d_max_m: float = 2.0  # laser returns nearer than this matter (the paper's d_max)
    side_sector_rad: float = math.pi / 2  # *_left / *_right look at this much in front of each side
    front_cone_rad: float = math.radians(10.0)  # circular_avoid: full width of the front cone
    circular_turn_rad: float = math.radians(30.0)  # circular_avoid: direction to its side
    sonar_threshold_m: float = 1.0  # sonar_avoid applies below this rear range
    reach_m: float = 0.75  # attract_<target> goal: the target seen within this range


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
class Observations:
    """What the primitives see, for ``N`` instants.

    ``ranges_m (N, B)`` with beam angles from ``geometry``; ``sonar_m (N, S)`` at
    ``sonar_angles_rad (S,)`` (None: no sonar); targets ``(N, T)`` arrays, NaN where unseen.
    """

    ranges_m: np.ndarray
    geometry: ScanGeometry
    sonar_m: np.ndarray | None
    sonar_angles_rad: np.ndarray | None
    sonar_max_m: float
    target_names: tuple[str, ...]
    target_bearing_rad: np.ndarray
    target_range_m: np.ndarray

    @staticmethod
    def from_detections(
        *,
        ranges_m: np.ndarray,
        geometry: ScanGeometry,
        detections: Sequence[Sequence[Detection]],
        target_names: Sequence[str],
        sonar_m: np.ndarray | None = None,
        sonar_angles_rad: np.ndarray | None = None,
        sonar_max_m: float = math.inf,
    ) -> Observations:
        n, t = len(ranges_m), len(target_names)
        bearing = np.full((n, t), np.nan)
        rng = np.full((n, t), np.nan)
        col = {name: i for i, name in enumerate(target_names)}
        for k, dets in enumerate(detections):
            for d in dets:
                j = col.get(d.name)
                if j is not None:
                    bearing[k, j], rng[k, j] = d.bearing_rad, d.range_m
        return Observations(
            np.atleast_2d(np.asarray(ranges_m, dtype=np.float64)),
            geometry,
            None if sonar_m is None else np.atleast_2d(np.asarray(sonar_m, dtype=np.float64)),
            sonar_angles_rad,
            sonar_max_m,
            tuple(target_names),
            bearing,
            rng,
        )


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


def _wrap(a: np.ndarray) -> np.ndarray:
    return np.asarray(np.arctan2(np.sin(a), np.cos(a)))


def _dot(weights: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """``Σᵢ wᵢ·dirᵢ``: ``(N, B) × (B, 2) → (N, 2)``.

    Row-wise reductions, not a BLAS matmul: each row's result is bit-identical whether it is
    computed alone (live) or in a batch (offline).
    """
    return np.column_stack([(weights * dirs[:, 0]).sum(axis=1), (weights * dirs[:, 1]).sum(axis=1)])


def _pool_strongest(weights: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Direction of ``Σ wᵢ·dirᵢ`` with length ``max wᵢ``: ``(N, B) × (B, 2) → (N, 2)``."""
    s = _dot(weights, dirs)
    norm = np.hypot(s[:, 0], s[:, 1])
    mag = weights.max(axis=1, initial=0.0)
    scale = np.divide(mag, norm, out=np.zeros_like(norm), where=norm > 1e-12)
    return np.asarray(s * scale[:, None])


def distinct_beams(g: ScanGeometry) -> np.ndarray:
    """``(B,)`` mask of beams whose bearing no earlier beam already has.

    A scanner sweeping more than a full turn (the Neato's 361 beams from −π to +π) repeats its
    first bearings at the end; counting them twice would tilt every sum toward the seam.

    >>> distinct_beams(ScanGeometry(-math.pi, math.pi / 180, 361, 5.0)).sum()
    np.int64(360)
    """
    own = np.ones(g.count, dtype=bool)
    step = abs(g.increment_rad)
    if g.count > 1 and step > 0 and step * (g.count - 1) >= 2 * math.pi - step / 2:
        own[int(round(2 * math.pi / step)) :] = False
    return own


def compute(
    obs: Observations, names: Sequence[str], params: BehaviorParams = BehaviorParams()
) -> BehaviorOutputs:
    """Outputs of the behaviours ``names`` on ``obs`` (see the module docstring)."""
    r = obs.ranges_m
    n = r.shape[0]
    g = obs.geometry
    ang = _wrap(g.angles)
    dirs = np.column_stack([np.cos(ang), np.sin(ang)])
    own = distinct_beams(g)  # a beam repeating an earlier bearing (360° + 1 scanners) is ignored
    valid = np.isfinite(r) & (r > 0.0) & (r < g.max_range_m) & own[None, :]
    d = params.d_max_m
    near = valid & (r < d)
    rn = np.where(near, r, d)  # ranges of near returns, d elsewhere
    front = (np.abs(ang) <= math.pi / 2 + 1e-9) & own
    left = (ang >= -1e-9) & (ang <= params.side_sector_rad + 1e-9) & own
    right = (ang <= 1e-9) & (ang >= -params.side_sector_rad - 1e-9) & own
    cone = (np.abs(ang) <= params.front_cone_rad / 2 + 1e-9) & own
    push = np.where(near, (d - rn) / d, 0.0)  # (N, B) repulsion strength

    k = len(names)
    vec = np.zeros((n, k, 2))
    app = np.zeros((n, k), dtype=bool)
    goal = np.zeros((n, k), dtype=bool)

    def wander(sector: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        open_ = ~near & sector[None, :]
        cnt = max(int(sector.sum()), 1)
        return _dot(open_.astype(np.float64), dirs) / cnt, open_.any(axis=1)

    def wall_attract(sector: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        hit = near & sector[None, :]
        s = _dot(hit.astype(np.float64), dirs)
        norm = np.hypot(s[:, 0], s[:, 1])
        rmin = np.where(hit, rn, np.inf).min(axis=1, initial=np.inf)
        mag = np.where(np.isfinite(rmin), rmin / d, 0.0)
        scale = np.divide(mag, norm, out=np.zeros_like(norm), where=norm > 1e-12)
        return np.asarray(s * scale[:, None]), hit.any(axis=1)

    def wall_side(sector: np.ndarray, turn: float) -> tuple[np.ndarray, np.ndarray]:
        hit = near & sector[None, :]
        tang = np.column_stack([np.cos(ang + turn), np.sin(ang + turn)])
        return _pool_strongest(np.where(hit, push, 0.0), tang), hit.any(axis=1)

    def circular(turn: float) -> tuple[np.ndarray, np.ndarray]:
        hit = near & cone[None, :]
        rmin = np.where(hit, rn, np.inf).min(axis=1, initial=np.inf)
        mag = np.where(np.isfinite(rmin), (d - rmin) / d, 0.0)
        return mag[:, None] * np.array([math.cos(turn), math.sin(turn)])[None, :], hit.any(axis=1)

    def sonar_avoid() -> tuple[np.ndarray, np.ndarray]:
        if obs.sonar_m is None or obs.sonar_angles_rad is None:
            return np.zeros((n, 2)), np.zeros(n, dtype=bool)
        s = obs.sonar_m
        thr = params.sonar_threshold_m
        ok = np.isfinite(s) & (s > 0.0) & (s < min(thr, obs.sonar_max_m))
        w = np.where(ok, (thr - np.where(ok, s, thr)) / thr, 0.0)
        sd = -np.column_stack([np.cos(obs.sonar_angles_rad), np.sin(obs.sonar_angles_rad)])
        return _pool_strongest(w, sd), ok.any(axis=1)

    for i, name in enumerate(names):
        if name == "avoid":
            v, a = _pool_strongest(push, -dirs), near.any(axis=1)
        elif name == "wander":
            v, a = wander(front)
        elif name == "wander_left":
            v, a = wander(left)
        elif name == "wander_right":
            v, a = wander(right)
        elif name == "wall_attract":
            v, a = wall_attract(front)
        elif name == "wall_attract_left":
            v, a = wall_attract(left)
        elif name == "wall_attract_right":
            v, a = wall_attract(right)
        elif name == "sonar_avoid":
            v, a = sonar_avoid()
        elif name == "wall_side_left":
            v, a = wall_side(left, -math.pi / 2)
        elif name == "wall_side_right":
            v, a = wall_side(right, math.pi / 2)
        elif name == "circular_avoid_left":
            v, a = circular(params.circular_turn_rad)
        elif name == "circular_avoid_right":
            v, a = circular(-params.circular_turn_rad)
        elif name.startswith(ATTRACT):
            tname = name[len(ATTRACT) :]
            if tname in obs.target_names:
                j = obs.target_names.index(tname)
                b, tr = obs.target_bearing_rad[:, j], obs.target_range_m[:, j]
                a = np.isfinite(b) & np.isfinite(tr)
                v = np.where(
                    a[:, None], np.column_stack([np.cos(np.nan_to_num(b)), np.sin(np.nan_to_num(b))]), 0.0
                )
                goal[:, i] = a & (np.nan_to_num(tr, nan=np.inf) <= params.reach_m)
            else:
                v, a = np.zeros((n, 2)), np.zeros(n, dtype=bool)
        else:
            raise ConfigError(f"unknown behaviour {name!r}")
        vec[:, i] = np.where(a[:, None], v, 0.0)
        app[:, i] = a
    return BehaviorOutputs(tuple(names), vec, app, goal)
