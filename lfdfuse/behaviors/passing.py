"""Openings passed by: which onsets of :mod:`lfdfuse.behaviors.openings` a drive counts.

* :class:`PassParams` — when an opening counts as passed by rather than turned into, and when
  a robot is coming back out of a dead end it strayed into.
* :class:`PassedCounter` — onsets → openings passed by on each side, one tick at a time (the
  runtime's sub-goal landmarks); :func:`passed_before` runs it over a log (segmentation). The
  same class over the teacher's demo and the robot's run gives both the same count.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lfdfuse.behaviors.openings import LEFT, RIGHT


@dataclass(frozen=True)
class PassParams:
    """When an opening counts as passed by rather than turned into (metres, radians)."""

    #: turned this far toward the opening's side, from the heading the sectors were held at
    #: when it was met, ...
    enter_rad: float = math.radians(45.0)
    #: ... within this much travel after it: the route turned into it (a corner, a turn-off);
    #: an opening driven past this far without that turn was passed by
    pass_m: float = 2.5
    #: an onset this close (travel) after the last one on its side is that opening flickering
    #: at its edge (met while turning, the sectors sweep its corner twice), not another one
    merge_m: float = 1.5
    #: an opening turned into, then turned round in (facing within ``180° − round_rad`` of the
    #: way back out) no deeper than ``dead_end_m`` past where it was met, is a dead end the robot
    #: comes back out of: what it counted in there is undone, and openings met on the way back
    #: out (the dead end's mouth, the corridor it left, seen the other way) are not passed, until
    #: it is back within ``mouth_m`` of the line it met the opening on (on its way in the corridor
    #: it left) and has driven ``merge_m`` on from there — or, wherever it is, ``2 · dead_end_m``
    #: after it turned round. Depths come from odometry (the increments integrated), never a map
    dead_end_m: float = 8.0
    round_rad: float = math.radians(135.0)
    mouth_m: float = 0.5


class PassedCounter:
    """Openings passed by on each side since a start: onsets the robot did not turn into.

    Where an opening is met while turning (a corner cut short, a turn begun early) its onset
    comes and goes with the line each driver takes; an opening the route turns into is not one
    it passes by, whoever meets it. Counting only openings driven past gives the same count to
    a teacher and a robot on the same route. Fed one tick at a time (:meth:`update`); the count
    on a side at a tick is :attr:`before` (openings before this tick's onsets, passed or still
    undecided, not turned into).

    A robot that strays into a dead end (an alcove the teacher drove past) turns round in it and
    comes back out: the openings it meets on the way out are the dead end's mouth and the
    corridor it left, seen from the other way, not openings passed on the route. The excursion
    is undone (:attr:`PassParams.dead_end_m`): the counts go back to what they were when the
    robot met the opening it turned into, and nothing counts until it is back out
    (:attr:`leaving`). A driver who keeps to the route never turns round inside a dead end it
    turned into, so its counts are unchanged.
    """

    def __init__(self, params: PassParams = PassParams()) -> None:
        self.params = params
        self.passed = [0, 0]
        #: (side, odometry, held heading, x, y) of an onset not yet passed or turned into
        self._pending: list[tuple[int, float, float, float, float]] = []
        self._odo_m = 0.0
        self._heading = 0.0
        self._xy = (0.0, 0.0)  # odometry integrated: where the robot is from where it started
        self._last = [-math.inf, -math.inf]  # odometry of the last onset per side
        #: the openings turned into, outermost first, each while the robot is less than
        #: ``dead_end_m`` past it: where it was met (x, y), the heading into it, and the counts
        #: then (passed; the openings still undecided that were met before it)
        self._into: list[
            tuple[float, float, float, tuple[int, int], list[tuple[int, float, float, float, float]]]
        ] = []
        #: coming back out of a dead end: the line it was met on (x, y, heading into it), the
        #: odometry from which it is back out (inf: not yet) and that at which it turned round
        self._out: tuple[float, float, float] | None = None
        self._out_from = math.inf
        self._round_at = 0.0
        #: coming back out of a dead end the robot turned round in: onsets are not openings passed
        self.leaving = False
        #: per side, openings met before this tick and not turned into
        self.before = (0, 0)
        #: per side, whether this tick's onset is a new opening (not one flickering at its edge)
        self.new = (False, False)

    def update(self, onset: tuple[bool, bool], step_m: float, turn_rad: float, held_turn_rad: float) -> None:
        """This tick's onsets (left, right), odometry increment (m, rad), and how far the robot
        has turned from the heading the sectors are held at (rad, + = left)."""
        self._odo_m += step_m
        self._heading += turn_rad
        x, y = self._xy
        self._xy = (x + step_m * math.cos(self._heading), y + step_m * math.sin(self._heading))
        keep = []
        into: tuple[float, float, float, float] | None = None
        for side, odo, held, ox, oy in self._pending:
            sign = 1.0 if side == LEFT else -1.0
            if sign * (self._heading - held) >= self.params.enter_rad:
                into = (ox, oy, held + sign * math.pi / 2, odo)  # turned into: not passed
                continue
            if self._odo_m - odo >= self.params.pass_m:
                self.passed[side] += 1
                continue
            keep.append((side, odo, held, ox, oy))
        self._pending = keep
        if into is not None:  # kept, with the counts at its onset, in case it is a dead end
            met_before = [e for e in keep if e[1] < into[3]]
            self._into.append((*into[:3], (self.passed[LEFT], self.passed[RIGHT]), met_before))
        self._dead_end()
        waiting = (
            [sum(1 for e in self._pending if e[0] == side) for side in (LEFT, RIGHT)]
            if self._pending
            else [0, 0]
        )
        self.before = (self.passed[LEFT] + waiting[LEFT], self.passed[RIGHT] + waiting[RIGHT])
        new = [False, False]
        for side in (LEFT, RIGHT):
            if onset[side]:
                if self.leaving:
                    continue  # the dead end's mouth, the corridor it left: not passed on the route
                if self._odo_m - self._last[side] >= self.params.merge_m:
                    held = self._heading - held_turn_rad
                    self._pending.append((side, self._odo_m, held, *self._xy))
                    new[side] = True
                self._last[side] = self._odo_m
        self.new = (new[LEFT], new[RIGHT])

    def _depth(self, x0: float, y0: float, heading_in: float) -> float:
        """How far the robot is past the line (through ``x0, y0``) it met an opening on, into it."""
        return (self._xy[0] - x0) * math.cos(heading_in) + (self._xy[1] - y0) * math.sin(heading_in)

    def _dead_end(self) -> None:
        """Turned round in an opening turned into: undo the excursion; back out: count again.

        The outermost one the robot has turned round in counts: a robot wiggling in a dead end
        turns into gaps of its own walls, and turning on round in the outer one undoes that too."""
        # past dead_end_m: a corridor the route follows on, not a dead end
        self._into = [e for e in self._into if self._depth(*e[:3]) <= self.params.dead_end_m]
        for k, (x0, y0, heading_in, counts, met_before) in enumerate(self._into):
            off = self._heading - heading_in
            if abs(math.atan2(math.sin(off), math.cos(off))) >= self.params.round_rad:
                del self._into[k:]  # the outer ones stay: the robot may yet turn round in them
                self.passed = [counts[0], counts[1]]
                self._pending = list(met_before)
                self._out, self._out_from, self._round_at = (x0, y0, heading_in), math.inf, self._odo_m
                break
        if self._out is not None:
            if self._out_from == math.inf and self._depth(*self._out) <= self.params.mouth_m:
                self._out_from = self._odo_m
            back = self._odo_m - self._out_from >= self.params.merge_m
            if back or self._odo_m - self._round_at >= 2.0 * self.params.dead_end_m:
                self._out = None
        self.leaving = self._out is not None


def passed_before(
    onsets: np.ndarray,
    step_m: np.ndarray,
    turn_rad: np.ndarray,
    held_rad: np.ndarray,
    params: PassParams = PassParams(),
) -> tuple[np.ndarray, np.ndarray]:
    """``(N, 2)`` :attr:`PassedCounter.before` and ``(N, 2)`` :attr:`PassedCounter.new` at each
    tick of a log's cues, counted from its first tick."""
    counter = PassedCounter(params)
    before = np.zeros((len(onsets), 2), dtype=np.int64)
    new = np.zeros((len(onsets), 2), dtype=bool)
    for i in range(len(onsets)):
        counter.update(
            (bool(onsets[i, 0]), bool(onsets[i, 1])), float(step_m[i]), float(turn_rad[i]), float(held_rad[i])
        )
        before[i], new[i] = counter.before, counter.new
    return before, new
