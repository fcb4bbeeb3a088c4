"""Landmarks a robot recognises from its own sensors: side openings and odometry (issue 15).

A purely reactive network cannot know *where* a person turned off the route. What it can
sense, without a map: an *opening* on its left or right (a junction, a door: most beams of a
side sector reach far), and how far it drove and how much it turned since some event
(odometry). The same code runs over a whole log (segmentation) and one scan at a time
(execution), so what the demo saw is what the robot will see.

* :func:`side_openings` — ``(N, B)`` scans → ``(N, 2)`` open flags (left, right).
* :class:`OpeningTracker` — open flags → *onsets* with hysteresis (an opening is entered once,
  however the beams flicker at its edges); :func:`opening_onsets` runs it over a log.
* :func:`odometry_increments` — ``(N, 3)`` poses → distance (m) and signed heading change
  (rad) per step: relative motion only, as wheel odometry gives it.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from lfdfuse.sim.sensors import ScanGeometry

LEFT, RIGHT = 0, 1
SIDES = ("left", "right")


@dataclass(frozen=True)
class OpeningParams:
    """What counts as an opening on a side (metres, radians, control periods)."""

    inner_rad: float = math.radians(60.0)  # the side sector spans these bearings from straight ahead
    outer_rad: float = math.radians(120.0)
    open_m: float = 3.0  # a beam this long passes into the opening (corridors here are ≤ 2.6 m wide)
    fraction: float = 0.5  # this share of the sector's beams must be that long
    on_ticks: int = 2  # open this many ticks in a row: entered
    off_ticks: int = 4  # closed this many ticks in a row: left behind
    #: openings count only while driving steadily: turning by more than this over the last
    #: ``steady_ticks`` (turning round in a dead end, into a corridor) sweeps the sectors
    #: over openings that are not junctions passed
    steady_rad: float = math.radians(25.0)
    steady_ticks: int = 8


def side_openings(
    ranges_m: np.ndarray,
    geometry: ScanGeometry,
    params: OpeningParams,
    *,
    offset_rad: np.ndarray | None = None,
) -> np.ndarray:
    """``(N, 2)`` bool: is there an opening on the left / right, per scan ``(N, B)``.

    A beam with no return (inf, NaN, ≤ 0 or at max range) reaches far. A scanner that does not
    cover a side sector never sees an opening there. ``offset_rad (N,)`` turns the sectors of
    each scan by that angle (+ = left): sectors fixed to an earlier heading, for a robot that
    has already begun to turn.
    """
    r = np.atleast_2d(np.asarray(ranges_m, dtype=np.float64))
    a = np.arctan2(np.sin(geometry.angles), np.cos(geometry.angles))[None, :]
    if offset_rad is not None:
        a = a - np.asarray(offset_rad, dtype=np.float64).reshape(-1, 1)
        a = np.arctan2(np.sin(a), np.cos(a))
    far = ~np.isfinite(r) | (r <= 0.0) | (r >= min(params.open_m, geometry.max_range_m))
    out = np.zeros((r.shape[0], 2), dtype=bool)
    for side, sign in ((LEFT, 1.0), (RIGHT, -1.0)):
        sector = np.broadcast_to((sign * a >= params.inner_rad) & (sign * a <= params.outer_rad), r.shape)
        count = sector.sum(axis=1)
        share = np.divide((far & sector).sum(axis=1), count, out=np.zeros(len(r)), where=count > 0)
        out[:, side] = (count > 0) & (share >= params.fraction)
    return out


class OpeningTracker:
    """Turns per-tick open flags into onsets, with hysteresis (one tick at a time)."""

    def __init__(self, params: OpeningParams = OpeningParams()) -> None:
        self.params = params
        self.inside = [False, False]
        self._run = [0, 0]  # ticks the flag has disagreed with ``inside``
        self._turns: deque[float] = deque(maxlen=params.steady_ticks)

    def update(self, open_now: np.ndarray, turn_rad: float = 0.0) -> tuple[bool, bool]:
        """Onset (left, right) at this tick from its open flags ``(2,)`` and this tick's
        heading change (rad); while turning, the sides read as closed."""
        self._turns.append(turn_rad)
        steady = abs(sum(self._turns)) <= self.params.steady_rad
        onset = [False, False]
        for s in (LEFT, RIGHT):
            if (bool(open_now[s]) and steady) != self.inside[s]:
                self._run[s] += 1
                need = self.params.off_ticks if self.inside[s] else self.params.on_ticks
                if self._run[s] >= need:
                    self.inside[s] = not self.inside[s]
                    self._run[s] = 0
                    onset[s] = self.inside[s]
            else:
                self._run[s] = 0
        return onset[0], onset[1]


def opening_onsets(
    open_flags: np.ndarray, turn_rad: np.ndarray, params: OpeningParams = OpeningParams()
) -> np.ndarray:
    """``(N, 2)`` bool onsets from ``(N, 2)`` open flags and ``(N,)`` heading changes,
    exactly as the live tracker sees them."""
    tr = OpeningTracker(params)
    return np.array(
        [tr.update(f, float(w)) for f, w in zip(open_flags, turn_rad, strict=True)], dtype=bool
    ).reshape(-1, 2)


def odometry_increments(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance (m) and signed heading change (rad, + = left) of each step ``(N,)``; 0 for the first."""
    p = np.asarray(pose, dtype=np.float64).reshape(-1, 3)
    dist = np.zeros(len(p))
    turn = np.zeros(len(p))
    if len(p) > 1:
        dist[1:] = np.hypot(np.diff(p[:, 0]), np.diff(p[:, 1]))
        d = np.diff(p[:, 2])
        turn[1:] = np.arctan2(np.sin(d), np.cos(d))
    return dist, turn
