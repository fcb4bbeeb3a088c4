"""``avoid`` (LA) and ``sonar_avoid`` (SA): away from what is near, by laser or by rear sonar.

Direction of the summed repulsions, length of the strongest one, ``(d − r) / d``: it grows as the
robot nears the object. A log without sonar makes ``sonar_avoid`` never applicable.
"""

from __future__ import annotations

import numpy as np

from lfdfuse.behaviors.spec import BehaviorSpec, Result, Scan, pool_strongest, stateless


def avoid(s: Scan) -> Result:
    return Result(pool_strongest(s.push, s.beams.away), np.asarray(s.near.any(axis=1)))


def sonar_avoid(s: Scan) -> Result:
    obs = s.obs
    if obs.sonar_m is None or obs.sonar_angles_rad is None:
        return Result(np.zeros((s.n, 2)), np.zeros(s.n, dtype=bool))
    sonar = obs.sonar_m
    thr = s.params.sonar_threshold_m
    ok = np.isfinite(sonar) & (sonar > 0.0) & (sonar < min(thr, obs.sonar_max_m))
    w = np.where(ok, (thr - np.where(ok, sonar, thr)) / thr, 0.0)
    sd = -np.column_stack([np.cos(obs.sonar_angles_rad), np.sin(obs.sonar_angles_rad)])
    return Result(pool_strongest(w, sd), ok.any(axis=1))


SPECS = (
    BehaviorSpec(
        "avoid",
        "LA",
        "#444444",
        0,
        stateless(avoid, ("avoid", "", 0.0)),
        default_role="fixed",
        default_weight=1.0,
        meaning="away from laser returns nearer than d_max",
    ),
    BehaviorSpec(
        "sonar_avoid",
        "SA",
        "#999999",
        7,
        stateless(sonar_avoid, ("sonar_avoid", "", 0.0)),
        inputs=frozenset({"sonar"}),
        default_role="fixed",
        default_weight=0.5,
        meaning="away from rear sonar returns below the threshold",
    ),
)
