"""``circular_avoid_left`` (CAL), ``circular_avoid_right`` (CAR): round an obstacle ahead.

Applicable when a return nearer than ``d_max`` lies in the front cone; the vector points
``circular_turn_rad`` to its side, length ``(d − r_min) / d`` of the cone.
"""

from __future__ import annotations

import math

import numpy as np

from lfdfuse.behaviors.spec import BehaviorSpec, Result, Scan, stateless


def circular(s: Scan, side: float) -> Result:
    d = s.params.d_max_m
    turn = side * s.params.circular_turn_rad
    hit = s.near & s.cone[None, :]
    rmin = np.where(hit, s.rn, np.inf).min(axis=1, initial=np.inf)
    mag = np.where(np.isfinite(rmin), (d - rmin) / d, 0.0)
    return Result(mag[:, None] * np.array([math.cos(turn), math.sin(turn)])[None, :], hit.any(axis=1))


SPECS = (
    BehaviorSpec(
        "circular_avoid_left",
        "CAL",
        "#CC79A7",
        10,
        stateless(lambda s: circular(s, 1.0)),
        meaning="30° to the left of an obstacle in the front cone",
    ),
    BehaviorSpec(
        "circular_avoid_right",
        "CAR",
        "#E8B5D2",
        11,
        stateless(lambda s: circular(s, -1.0)),
        hatch="//",
        meaning="30° to the right of an obstacle in the front cone",
    ),
)
