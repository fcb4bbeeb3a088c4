"""Walls: ``wall_attract*`` (WF, WFL, WFR) toward them, ``wall_side_*`` (WSL, WSR) along them.

``wall_attract*`` points toward the returns nearer than ``d_max`` (the wall normal) with length
``r_min / d``: a spring — with ``avoid`` it has an equilibrium distance set by the weights, which
is how a learned fusion holds a distance to its wall. ``wall_side_*`` is tangent to the near
returns on its side (turned away from the wall), direction of the summed contributions, length
of the strongest, ``(d − r) / d``.
"""

from __future__ import annotations

import math

import numpy as np

from lfdfuse.behaviors.spec import BehaviorSpec, Result, Scan, dot, pool_strongest, stateless


def wall_attract_in(s: Scan, sector: np.ndarray) -> Result:
    d = s.params.d_max_m
    hit = s.near & sector[None, :]
    v = dot(hit.astype(np.float64), s.dirs)
    norm = np.hypot(v[:, 0], v[:, 1])
    rmin = np.where(hit, s.rn, np.inf).min(axis=1, initial=np.inf)
    mag = np.where(np.isfinite(rmin), rmin / d, 0.0)
    scale = np.divide(mag, norm, out=np.zeros_like(norm), where=norm > 1e-12)
    return Result(np.asarray(v * scale[:, None]), hit.any(axis=1))


def wall_side_in(s: Scan, sector: np.ndarray, turn: float) -> Result:
    hit = s.near & sector[None, :]
    return Result(pool_strongest(np.where(hit, s.push, 0.0), s.beams.tangent(turn)), hit.any(axis=1))


SPECS = (
    BehaviorSpec(
        "wall_attract",
        "WF",
        "#0072B2",
        4,
        stateless(lambda s: wall_attract_in(s, s.front), ("wall_attract", "front", 0.0)),
        meaning="toward objects nearer than d_max in the front half",
    ),
    BehaviorSpec(
        "wall_attract_left",
        "WFL",
        "#0072B2",
        5,
        stateless(lambda s: wall_attract_in(s, s.left), ("wall_attract", "left", 0.0)),
        meaning="toward objects nearer than d_max on the left",
    ),
    BehaviorSpec(
        "wall_attract_right",
        "WFR",
        "#56B4E9",
        6,
        stateless(lambda s: wall_attract_in(s, s.right), ("wall_attract", "right", 0.0)),
        hatch="//",
        meaning="toward objects nearer than d_max on the right",
    ),
    BehaviorSpec(
        "wall_side_left",
        "WSL",
        "#009E73",
        8,
        stateless(lambda s: wall_side_in(s, s.left, -math.pi / 2), ("wall_side", "left", -math.pi / 2)),
        meaning="along objects nearer than d_max on the left",
    ),
    BehaviorSpec(
        "wall_side_right",
        "WSR",
        "#6FD3B3",
        9,
        stateless(lambda s: wall_side_in(s, s.right, math.pi / 2), ("wall_side", "right", math.pi / 2)),
        hatch="//",
        meaning="along objects nearer than d_max on the right",
    ),
)
