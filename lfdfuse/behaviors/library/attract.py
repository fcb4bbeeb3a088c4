"""``attract_<target>`` (the paper's BA1..): toward a named target the camera sees.

A unit vector toward the target; applicable while it is seen; its goal is met when it is seen
within ``reach_m``. A log without camera detections makes it never applicable.
"""

from __future__ import annotations

import numpy as np

from lfdfuse.behaviors.spec import ATTRACT, BehaviorParams, BehaviorSpec, Result, Scan


class Attract:
    """Toward one target, by name."""

    def __init__(self, name: str, _params: BehaviorParams) -> None:
        self.target = name[len(ATTRACT) :]

    def reset(self) -> None:
        pass

    def step(self, s: Scan) -> Result:
        obs = s.obs
        if self.target not in obs.target_names:
            return Result(np.zeros((s.n, 2)), np.zeros(s.n, dtype=bool), np.zeros(s.n, dtype=bool))
        j = obs.target_names.index(self.target)
        b, tr = obs.target_bearing_rad[:, j], obs.target_range_m[:, j]
        a = np.isfinite(b) & np.isfinite(tr)
        # where ``a`` holds both are finite; elsewhere the vector is zeroed and the goal unmet
        bb = np.where(a, b, 0.0)
        v = np.where(a[:, None], np.column_stack([np.cos(bb), np.sin(bb)]), 0.0)
        goal = a & (np.where(a, tr, np.inf) <= s.params.reach_m)
        return Result(v, a, goal)


SPECS = (
    BehaviorSpec(
        ATTRACT,
        "BA",  # abbreviated by its target's name, as the map labels it
        "",  # drawn in its target's colour
        100,
        Attract,
        inputs=frozenset({"camera"}),
        family=True,
        meaning="toward the named target; goal: the target reached",
    ),
)
