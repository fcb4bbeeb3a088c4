"""The behaviour network runtime (paper Section III, DESIGN §8).

Each tick: behaviour outputs → the active step (the first step whose goal is not yet achieved;
a nested network is active until its last goal is achieved) → the BAC of this instant → that
step's weights for the BAC, or the default weights when the BAC was never seen in training (the
step's own ``default_weights`` when it has them, else the table's) → fused vector, kept to the
way a sub-goal step goes: in a step that drives on to a side opening, within :data:`DRIVE_ON_RAD`
of the held heading while the way ahead is open; in a turn, never to the other side; after a
turn, within :data:`SETTLE_RAD` of the heading it ended on for :data:`SETTLE_M`. Goals are
monitored for the active step only, so a task that visits the same target twice ("A then B then
A") needs it reached twice, in order; a goal once achieved stays achieved.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from lfdfuse.behaviors.primitives import BehaviorOutputs
from lfdfuse.network.landmark_goals import Cues, Progress
from lfdfuse.network.table import FusionTable, Network, Step

Path = tuple[int, ...]

#: a drive-on step to a side opening (the way ahead goes on there) keeps the fused heading within
#: this of the heading the opening sectors are held at, while the way ahead is open: the robot
#: drives past the openings before the n-th as the teacher did, instead of being drawn into one
#: by the style's pull toward open space (measured on the generated worlds)
DRIVE_ON_RAD = math.radians(30.0)

#: the step after a turn keeps the fused heading within this of the heading the turn ended on for
#: :data:`SETTLE_M` of travel, where the way ahead was open as the turn ended: a robot that turned
#: tighter than the teacher ends its turn at the mouth of the new corridor, not in it, and the
#: next step's rows (learned where the teacher drove along that corridor) can pull it back toward
#: the open way behind (the turn out of a spur at a T, measured on the generated worlds)
SETTLE_RAD = math.radians(15.0)
SETTLE_M = 2.0


@dataclass(frozen=True)
class Decision:
    """What the network decided at one tick."""

    step: Step | None  # the active fusion step (None: task complete)
    path: Path  # its position in the (nested) network
    bac: int
    #: the weights fused (a read-only view of the row's own, the same object every tick it is used)
    weights: Mapping[str, float]
    unseen: bool  # True when the BAC had no row and the default weights were used
    fused: np.ndarray  # (2,) robot-frame fused vector
    achieved_now: tuple[str, ...]  # goals achieved at this tick (target names)


_new = object.__new__
#: the weights of a decision with no step (the task complete)
_NO_WEIGHTS: Mapping[str, float] = MappingProxyType({})


def made_decision(
    step: Step | None,
    path: Path,
    bac: int,
    weights: Mapping[str, float],
    unseen: bool,
    fused: np.ndarray,
    achieved_now: tuple[str, ...],
) -> Decision:
    """``Decision(...)``, the same instance, without the frozen ``__init__``'s ``object.__setattr__``
    per field (half the cost, and a decision is made every tick)."""
    d = _new(Decision)
    d.__dict__.update(
        step=step, path=path, bac=bac, weights=weights, unseen=unseen, fused=fused, achieved_now=achieved_now
    )
    return d


class NetworkRuntime:
    """Owns the goal state of one execution of a fusion table."""

    def __init__(self, table: FusionTable) -> None:
        self.table = table
        self.achieved: set[Path] = set()
        self._has_goal = bool(table.goals())
        #: each behaviour's column in the outputs (the table's order)
        self._column = {name: i for i, name in enumerate(table.behaviors)}
        #: :meth:`active` and :attr:`complete` as of the number of paths achieved then (goals
        #: are only ever added: the same number, the same set)
        self._active_at: tuple[int, tuple[Path, Step] | None] | None = None
        self._complete_at: tuple[int, bool] | None = None
        #: what the active step has sensed since it began (its landmark decides from this)
        self.progress = Progress.fresh(0.0, _lag_of(self.active()))
        #: whether a step has a landmark: only a landmark decides from the cues (without one,
        #: nothing reads the progress, and it is not kept)
        self.senses = _has_landmark(table.network)
        #: the BAC of each applicability row of a tick, by its bytes (a few patterns recur)
        self._bacs: dict[bytes, int] = {}
        #: per set of weights decided with (by the id of the table's dict, which the entry keeps):
        #: a read-only view of it (a decision's weights are the same object tick after tick) and
        #: its (column, weight) pairs in its order, what :meth:`_fuse` sums
        self._views: dict[int, tuple[dict[str, float], Mapping[str, float], list[tuple[int, float]]]] = {}

    def active(self) -> tuple[Path, Step] | None:
        """The active fusion step, depth first; None when every goal is achieved."""
        cached = self._active_at
        if cached is not None and cached[0] == len(self.achieved):
            return cached[1]
        found = self._active(self.table.network, ())
        self._active_at = (len(self.achieved), found)  # after: a finished subnetwork adds its node
        return found

    def _active(self, net: Network, prefix: Path) -> tuple[Path, Step] | None:
        for i, step in enumerate(net.steps):
            path = (*prefix, i)
            if path in self.achieved:
                continue
            if step.network is not None:
                inner = self._active(step.network, path)
                if inner is None:
                    self.achieved.add(path)  # the subnetwork finished: the node's goal is met
                    continue
                return inner
            return path, step
        return None

    @property
    def complete(self) -> bool:
        """Every goal achieved (a network without goals runs until stopped)."""
        if not self._has_goal:
            return False
        found = self.active()
        cached = self._complete_at
        if cached is not None and cached[0] == len(self.achieved):
            return cached[1]
        done = found is None or not self._goal_ahead(self.table.network, ())
        self._complete_at = (len(self.achieved), done)
        return done

    def _goal_ahead(self, net: Network, prefix: Path) -> bool:
        """Whether an unachieved step with a goal remains."""
        for i, step in enumerate(net.steps):
            path = (*prefix, i)
            if path in self.achieved:
                continue
            if step.goal is not None:
                return True
            if step.network is not None and self._goal_ahead(step.network, path):
                return True
        return False

    def decide(self, outputs: BehaviorOutputs, reached: set[str], cues: Cues | None = None) -> Decision:
        """One tick: ``outputs`` of the table's behaviours (N = 1), ``reached`` targets now,
        ``cues`` the landmark cues of this tick (openings, odometry; None: nothing sensed)."""
        achieved_now: list[str] = []
        cues = cues or Cues()
        if self.senses:
            self.progress.add(cues)
        found = self.active()
        while found is not None:
            done = self._achieved_by(found[0], reached)
            if done is None:
                break
            self.achieved.add(done)
            ended = self._step_at(done)
            found = self.active()
            # a sub-goal's landmark counts from its step's start; a turn, from the heading held
            # then (by the sensor the step's landmark is sensed with)
            lag = _lag_of(found)
            self.progress = Progress.fresh(cues.seen_with(lag).held_turn_rad, lag)
            # settles only where the way ahead is open as the turn ends (not a turn into a dead end)
            turned = ended.landmark is not None and ended.landmark.kind == "turned"
            self.progress.after_turn = turned and cues.front_open
            if ended.goal is not None:
                achieved_now.append(ended.goal)
        app = outputs.applicable
        if app.shape[0] == 1 and app.dtype == np.bool_:
            # BehaviorOutputs.bac of the one tick, without its array, once per pattern
            flags = app[0]
            key = flags.tobytes()
            known = self._bacs.get(key)
            if known is None:
                if len(self._bacs) >= 4096:
                    self._bacs.clear()
                known = self._bacs[key] = sum(1 << j for j, a in enumerate(flags.tolist()) if a)
            bac = known
        else:
            bac = int(outputs.bac[0])
        if found is None or self.complete:
            return made_decision(None, (), bac, _NO_WEIGHTS, False, np.zeros(2), tuple(achieved_now))
        path, step = found
        row = step.row(bac)
        fallback = step.default_weights if step.default_weights is not None else self.table.default_weights
        weights = row.weights if row is not None else fallback
        view = self._views.get(id(weights))
        if view is None or view[0] is not weights:
            column = self._column
            pairs = [(column[name], w) for name, w in weights.items()]
            view = self._views[id(weights)] = (weights, MappingProxyType(weights), pairs)
        vec = outputs.vectors[0].tolist()
        x = y = 0.0
        for c, w in view[2]:  # _fuse of the weights, their columns looked up once
            vx, vy = vec[c]
            x += w * vx
            y += w * vy
        # hypot(x, y) is at least |x| and |y|: only a vector within 1e-9 on both axes needs it
        if row is not None and abs(x) <= 1e-9 and abs(y) <= 1e-9 and float(np.hypot(x, y)) <= 1e-9:
            x, y = self._fuse(vec, fallback)
        fused = self._steer(np.array([x, y]), step, cues)
        return made_decision(step, path, bac, view[1], row is None, fused, tuple(achieved_now))

    def _steer(self, fused: np.ndarray, step: Step, cues: Cues) -> np.ndarray:
        """The fused vector, kept to the way a sub-goal step goes (its length kept)."""
        landmark = step.landmark
        if landmark is not None and landmark.drives_on and cues.ahead_open:
            # drive on past the openings before the one to turn into: along the held heading (of
            # the default sensor, whatever sensor the landmark is met with: sectors held further
            # back follow the robot's drift toward an opening more slowly)
            return keep_within(fused, -cues.held_turn_rad, DRIVE_ON_RAD)
        if landmark is not None and landmark.kind == "turned":
            # a turn to a side is met only by turning that way: where the turn's rows pull the
            # other way (the robot is not where the teacher turned), drive straight on instead
            sign = 1.0 if landmark.side == "left" else -1.0
            if sign * math.atan2(fused[1], fused[0]) < 0.0:
                return np.array([float(np.hypot(fused[0], fused[1])), 0.0])
            return fused
        if self.progress.after_turn and self.progress.travelled_m < SETTLE_M:
            # drive on into the corridor the turn faces: along the heading the turn ended on
            return keep_within(fused, -self.progress.heading_rad, SETTLE_RAD)
        return fused

    def _step_at(self, path: Path) -> Step:
        net, step = self.table.network, None
        for i in path:
            step = net.steps[i]
            if step.network is not None:
                net = step.network
        assert step is not None
        return step

    def _achieved_by(self, path: Path, reached: set[str]) -> Path | None:
        """The outermost step on ``path`` achieved now, or None.

        A leaf with a target goal is achieved when the target is reached. A sub-goal leaf (one
        with a landmark) is achieved when its landmark is met — or, with the rest of its node,
        when the node's target is reached early (a favourable change: the goal came into reach
        before the turn-off).
        """
        leaf = self._step_at(path)
        if leaf.landmark is None:
            return path if leaf.goal is not None and leaf.goal in reached else None
        for depth in range(1, len(path)):
            step = self._step_at(path[:depth])
            if step.goal is not None and step.goal in reached:
                return path[:depth]
        if leaf.landmark.met(self.progress):
            return path
        side = leaf.landmark.waits(self.progress)
        if side is not None:
            self.progress.waiting[side] = True
        return None

    def fuse(self, outputs: BehaviorOutputs, weights: Mapping[str, float]) -> np.ndarray:
        """``Σ w·v`` over the weighted behaviours (in Python floats: the same sums, in order,
        without a numpy call per behaviour)."""
        x, y = self._fuse(outputs.vectors[0].tolist(), weights)
        return np.array([x, y])

    def _fuse(self, vec: list[list[float]], weights: Mapping[str, float]) -> tuple[float, float]:
        """:meth:`fuse` of the output vectors ``vec (K, 2)`` as Python lists."""
        column = self._column
        x = y = 0.0
        for name, w in weights.items():
            vx, vy = vec[column[name]]
            x += w * vx
            y += w * vy
        return x, y


def _has_landmark(net: Network) -> bool:
    """Whether a step of ``net`` (or of a network nested in it) has a landmark."""
    return any(
        s.landmark is not None or (s.network is not None and _has_landmark(s.network)) for s in net.steps
    )


def _lag_of(found: tuple[Path, Step] | None) -> float | None:
    """The lag the landmark of the active step ``found`` is sensed with (None: the default)."""
    return None if found is None or found[1].landmark is None else found[1].landmark.lag_m


def keep_within(v: np.ndarray, centre_rad: float, half_rad: float) -> np.ndarray:
    """``v`` turned, its length kept, to within ``half_rad`` of the direction ``centre_rad`` (the
    nearer edge; ``v`` itself when within, or zero)."""
    n = float(np.hypot(v[0], v[1]))
    if n <= 1e-12:
        return v
    off = math.atan2(v[1], v[0]) - centre_rad
    off = math.atan2(math.sin(off), math.cos(off))
    if abs(off) <= half_rad:
        return v
    a = centre_rad + math.copysign(half_rad, off)
    return np.array([n * math.cos(a), n * math.sin(a)])


def step_name_of(path: Path, table: FusionTable) -> str:
    net: Network = table.network
    names = []
    for i in path:
        step = net.steps[i]
        names.append(step.name)
        if step.network is not None:
            net = step.network
    return "/".join(names)
