"""What a behaviour primitive is: its spec in the catalogue, what it sees, and what it computes.

A primitive (DESIGN §4) maps what the robot senses to a robot-frame vector with norm in [0, 1],
a precondition (applicable now?) and optionally a goal. Each one is described once, by a
:class:`BehaviorSpec` in a module of :mod:`lfdfuse.behaviors.library`: its name, the paper's
acronym, its colour in every figure, the inputs it needs, its role in the default weights and
how to make its :class:`Primitive` — the small object that computes it, scan block after scan
block, with whatever it must remember from one scan to the next.

The same primitive object computes a whole log offline (one block of ``N`` scans after
another) and a live run (blocks of one scan): a stateful primitive carries its state across
block boundaries, so the two give the same result (the blocks = live law, tested).

:class:`Scan` is one block of observations with the per-beam quantities most primitives share
(beam bearings, which returns count, which lie nearer than ``d_max``, the sectors), each
computed once per block and only when asked for.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Literal, Protocol

import numpy as np

from lfdfuse.robot.readings import Detection, ScanGeometry

#: the name prefix of the behaviours toward a target: ``attract_<target>``
ATTRACT = "attract_"

#: what a primitive may need besides nothing: the laser, the rear sonars, a camera reporting
#: targets, wheel odometry (increments only, never a map position)
Input = Literal["laser", "sonar", "camera", "odometry"]
INPUTS: tuple[Input, ...] = ("laser", "sonar", "camera", "odometry")


def attract_target(name: str) -> str | None:
    """The target of an ``attract_<target>`` behaviour (or goal name), else None.

    >>> attract_target("attract_red"), attract_target("avoid")
    ('red', None)
    """
    return name[len(ATTRACT) :] if name.startswith(ATTRACT) and len(name) > len(ATTRACT) else None


@dataclass(frozen=True)
class BehaviorParams:
    """Parameters of the primitives (metres, radians)."""

    d_max_m: float = 2.0  # laser returns nearer than this matter (the paper's d_max)
    side_sector_rad: float = math.pi / 2  # *_left / *_right look at this much in front of each side
    front_cone_rad: float = math.radians(10.0)  # circular_avoid: full width of the front cone
    circular_turn_rad: float = math.radians(30.0)  # circular_avoid: direction to its side
    sonar_threshold_m: float = 1.0  # sonar_avoid applies below this rear range
    reach_m: float = 0.75  # attract_<target> goal: the target seen within this range


@dataclass(frozen=True)
class Observations:
    """What the primitives see, for ``N`` instants in time order.

    ``ranges_m (N, B)`` with beam angles from ``geometry``; ``sonar_m (N, S)`` at
    ``sonar_angles_rad (S,)`` (None: no sonar); targets ``(N, T)`` arrays, NaN where unseen;
    ``pose (N, 3)`` odometry (x, y, heading; only increments between scans are used; None: no
    odometry).
    """

    ranges_m: np.ndarray
    geometry: ScanGeometry
    sonar_m: np.ndarray | None
    sonar_angles_rad: np.ndarray | None
    sonar_max_m: float
    target_names: tuple[str, ...]
    target_bearing_rad: np.ndarray
    target_range_m: np.ndarray
    pose: np.ndarray | None = None

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
        pose: np.ndarray | None = None,
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
            None if pose is None else np.atleast_2d(np.asarray(pose, dtype=np.float64)),
        )

    def rows(self, a: int, b: int) -> Observations:
        """The instants ``a`` to ``b`` (a block of scans)."""
        return Observations(
            self.ranges_m[a:b],
            self.geometry,
            None if self.sonar_m is None else self.sonar_m[a:b],
            self.sonar_angles_rad,
            self.sonar_max_m,
            self.target_names,
            self.target_bearing_rad[a:b],
            self.target_range_m[a:b],
            None if self.pose is None else self.pose[a:b],
        )


#: the ``(1, T)`` target rows of a tick with no target in sight: all NaN, read-only, one per T
_UNSEEN: dict[int, np.ndarray] = {}


def unseen(targets: int) -> np.ndarray:
    """The one all-NaN ``(1, targets)`` row, read-only: the bearings and ranges of a live tick
    that sees no target (a primitive knows it by identity and skips its targets)."""
    row = _UNSEEN.get(targets)
    if row is None:
        row = _UNSEEN[targets] = np.full((1, targets), np.nan)
        row.flags.writeable = False
    return row


def sees_none(obs: Observations) -> bool:
    """Whether ``obs`` is a live tick's that sees no target: its rows are :func:`unseen`'s."""
    rows = obs.target_bearing_rad
    return rows is obs.target_range_m and rows is _UNSEEN.get(rows.shape[1])


def made_observations(
    ranges_m: np.ndarray,
    geometry: ScanGeometry,
    sonar_m: np.ndarray | None,
    sonar_angles_rad: np.ndarray | None,
    sonar_max_m: float,
    target_names: tuple[str, ...],
    target_bearing_rad: np.ndarray,
    target_range_m: np.ndarray,
    pose: np.ndarray | None,
) -> Observations:
    """``Observations(...)``, the same instance, without the frozen ``__init__``'s
    ``object.__setattr__`` per field (half the cost: a live run makes one every tick)."""
    o = object.__new__(Observations)
    o.__dict__.update(
        ranges_m=ranges_m,
        geometry=geometry,
        sonar_m=sonar_m,
        sonar_angles_rad=sonar_angles_rad,
        sonar_max_m=sonar_max_m,
        target_names=target_names,
        target_bearing_rad=target_bearing_rad,
        target_range_m=target_range_m,
        pose=pose,
    )
    return o


def wrap(a: np.ndarray) -> np.ndarray:
    return np.asarray(np.arctan2(np.sin(a), np.cos(a)))


def dot(weights: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """``Σᵢ wᵢ·dirᵢ``: ``(N, B) × (B, 2) → (N, 2)``.

    Row-wise reductions, not a BLAS matmul: each row's result is bit-identical whether it is
    computed alone (live) or in a batch (offline).
    """
    out = np.empty((weights.shape[0], 2))
    out[:, 0] = (weights * dirs[:, 0]).sum(axis=1)
    out[:, 1] = (weights * dirs[:, 1]).sum(axis=1)
    return out


def pool_strongest(weights: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Direction of ``Σ wᵢ·dirᵢ`` with length ``max wᵢ``: ``(N, B) × (B, 2) → (N, 2)``."""
    s = dot(weights, dirs)
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


class Scan:
    """A block of ``N`` observations and the per-beam quantities the primitives share.

    A beam has *no return* when its range is inf, NaN, ≤ 0, or at/above the scanner's max range
    (the sentinel real scanners and our logs use); such beams count as open space. Sectors are
    chosen by beam bearing, never by beam index, so any scanner geometry works; a beam repeating
    an earlier bearing (a 360° + 1 scanner) belongs to no sector.
    """

    def __init__(self, obs: Observations, params: BehaviorParams) -> None:
        self.obs = obs
        self.params = params
        self.r = obs.ranges_m
        self.n = int(self.r.shape[0])

    @cached_property
    def beams(self) -> Beams:
        """The scanner's beam layout as the primitives see it (computed once per layout)."""
        return beams_of(self.obs.geometry, self.params)

    @property
    def ang(self) -> np.ndarray:
        """``(B,)`` beam bearings in (−π, π]."""
        return self.beams.ang

    @property
    def dirs(self) -> np.ndarray:
        """``(B, 2)`` unit vectors along the beams."""
        return self.beams.dirs

    @property
    def own(self) -> np.ndarray:
        """``(B,)`` beams whose bearing no earlier beam has (:func:`distinct_beams`)."""
        return self.beams.own

    @cached_property
    def valid(self) -> np.ndarray:
        """``(N, B)`` returns that count (finite, positive, below max range, own bearing)."""
        r = self.r
        return np.asarray(
            np.isfinite(r) & (r > 0.0) & (r < self.obs.geometry.max_range_m) & self.own[None, :]
        )

    @cached_property
    def near(self) -> np.ndarray:
        """``(N, B)`` returns nearer than ``d_max``."""
        return np.asarray(self.valid & (self.r < self.params.d_max_m))

    @cached_property
    def rn(self) -> np.ndarray:
        """``(N, B)`` ranges of near returns, ``d_max`` elsewhere."""
        return np.where(self.near, self.r, self.params.d_max_m)

    @cached_property
    def push(self) -> np.ndarray:
        """``(N, B)`` repulsion strength ``(d_max − r) / d_max`` of near returns, 0 elsewhere."""
        d = self.params.d_max_m
        return np.where(self.near, (d - self.rn) / d, 0.0)

    @property
    def front(self) -> np.ndarray:
        """``(B,)`` beams in the front half."""
        return self.beams.front

    @property
    def left(self) -> np.ndarray:
        """``(B,)`` beams from straight ahead to ``side_sector_rad`` to the left."""
        return self.beams.left

    @property
    def right(self) -> np.ndarray:
        """``(B,)`` beams from straight ahead to ``side_sector_rad`` to the right."""
        return self.beams.right

    @property
    def cone(self) -> np.ndarray:
        """``(B,)`` beams in the front cone of ``front_cone_rad``."""
        return self.beams.cone


class Beams:
    """What a scanner's beam layout gives every scan: bearings, directions and sectors.

    A function of the geometry and the parameters alone, so computed once per layout
    (:func:`beams_of`) rather than once per block: a live run computes blocks of one scan.
    The arrays are read-only.
    """

    def __init__(self, geometry: ScanGeometry, params: BehaviorParams) -> None:
        ang = wrap(geometry.angles)
        own = distinct_beams(geometry)
        self.ang = ang
        self.dirs = np.column_stack([np.cos(ang), np.sin(ang)])
        self.own = own
        self.front = np.asarray((np.abs(ang) <= math.pi / 2 + 1e-9) & own)
        self.left = np.asarray((ang >= -1e-9) & (ang <= params.side_sector_rad + 1e-9) & own)
        self.right = np.asarray((ang <= 1e-9) & (ang >= -params.side_sector_rad - 1e-9) & own)
        self.cone = np.asarray((np.abs(ang) <= params.front_cone_rad / 2 + 1e-9) & own)
        self.away = -self.dirs
        self._tangents: dict[float, np.ndarray] = {}
        for a in (self.ang, self.dirs, self.own, self.front, self.left, self.right, self.cone, self.away):
            a.flags.writeable = False

    def tangent(self, turn: float) -> np.ndarray:
        """``(B, 2)`` unit vectors at ``turn`` (rad) from each beam (read-only)."""
        t = self._tangents.get(turn)
        if t is None:
            t = np.column_stack([np.cos(self.ang + turn), np.sin(self.ang + turn)])
            t.flags.writeable = False
            self._tangents[turn] = t
        return t


@lru_cache(maxsize=32)
def beams_of(geometry: ScanGeometry, params: BehaviorParams) -> Beams:
    """The :class:`Beams` of a layout, cached (a run has one or two layouts)."""
    return Beams(geometry, params)


@dataclass(frozen=True)
class Result:
    """A primitive over a block: ``vector (N, 2)``, ``applicable (N,)``, ``goal (N,)`` (None: the
    primitive has no goal). The vector of an inapplicable instant is zeroed by the caller."""

    vector: np.ndarray
    applicable: np.ndarray
    goal: np.ndarray | None = None


class Primitive(Protocol):
    """One behaviour of a set, computing block after block of scans in time order.

    ``reset`` forgets what earlier scans left (a new log, a new run); ``step`` computes a block
    and keeps what the next block needs. A stateless primitive keeps nothing.
    """

    def reset(self) -> None: ...

    def step(self, scan: Scan) -> Result: ...


#: a primitive :func:`~lfdfuse.behaviors.primitives.compute` may run in its fused compiled loop
#: (:data:`~lfdfuse.behaviors.kernels.POOL`): its kind, the sector it looks at (``front``,
#: ``left``, ``right``; "" for all) and the turn of its pooled directions from the beams
Fused = tuple[Literal["avoid", "sonar_avoid", "wander", "wall_attract", "wall_side"], str, float]


class Stateless:
    """A primitive that remembers nothing between scans: a function of the block alone.

    ``fused`` says which compiled loop computes the same outputs (None: only ``fn`` does)."""

    def __init__(self, fn: Callable[[Scan], Result], fused: Fused | None = None) -> None:
        self.fn = fn
        self.fused = fused

    def reset(self) -> None:
        pass

    def step(self, scan: Scan) -> Result:
        return self.fn(scan)


#: a behaviour's part in the weights a table uses for BACs it never saw: none; a fixed weight
#: (``avoid`` 1, ``sonar_avoid`` 0.5); or an equal share of 1 among the set's wanderers
DefaultRole = Literal["none", "fixed", "share"]


@dataclass(frozen=True)
class BehaviorSpec:
    """One entry of the catalogue: everything the rest of lfdfuse knows about a behaviour.

    ``name`` is the canonical name, or with ``family`` the prefix of a family of names
    (``attract_`` for ``attract_<target>``); ``rank`` orders the catalogue (``BASE_BEHAVIORS``,
    error messages, the ``full`` preset's order); ``make(name, params)`` builds the primitive
    for one name of the spec. ``color`` is a ``#RRGGBB`` hex colour ("" for a family drawn in its
    target's colour), ``hatch`` tells a right variant from its left one in greyscale print.
    """

    name: str
    acronym: str
    color: str
    rank: int
    make: Callable[[str, BehaviorParams], Primitive]
    inputs: frozenset[Input] = frozenset({"laser"})
    default_role: DefaultRole = "none"
    default_weight: float = 0.0
    hatch: str = ""
    family: bool = False
    meaning: str = ""

    def names(self, name: str) -> bool:
        """Whether ``name`` is this behaviour (or a member of this family)."""
        return name.startswith(self.name) and len(name) > len(self.name) if self.family else name == self.name


def stateless(
    fn: Callable[[Scan], Result], fused: Fused | None = None
) -> Callable[[str, BehaviorParams], Primitive]:
    """A spec's ``make`` for a primitive that is a function of the block alone (``fused``: the
    compiled loop that computes it too, see :class:`Stateless`)."""
    return lambda _name, _params: Stateless(fn, fused)
