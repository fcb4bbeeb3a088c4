"""``wander`` (W), ``wander_left`` (WL), ``wander_right`` (WR): toward open space.

The mean of unit vectors over the sector's beams with no return nearer than ``d_max``: long when
the open space is wide and straight ahead. ``wander`` looks at the front half, the sides at the
90° in front of their side.
"""

from __future__ import annotations

import numpy as np

from lfdfuse.behaviors.spec import BehaviorSpec, Result, Scan, dot, stateless


def wander_in(s: Scan, sector: np.ndarray) -> Result:
    open_ = ~s.near & sector[None, :]
    cnt = max(int(sector.sum()), 1)
    return Result(dot(open_.astype(np.float64), s.dirs) / cnt, open_.any(axis=1))


SPECS = (
    BehaviorSpec(
        "wander",
        "W",
        "#E69F00",
        1,
        stateless(lambda s: wander_in(s, s.front), ("wander", "front", 0.0)),
        default_role="share",
        meaning="toward open directions in the front half",
    ),
    BehaviorSpec(
        "wander_left",
        "WL",
        "#E69F00",
        2,
        stateless(lambda s: wander_in(s, s.left), ("wander", "left", 0.0)),
        default_role="share",
        meaning="toward open directions in the 90° in front of the left side",
    ),
    BehaviorSpec(
        "wander_right",
        "WR",
        "#F5C85C",
        3,
        stateless(lambda s: wander_in(s, s.right), ("wander", "right", 0.0)),
        default_role="share",
        hatch="//",
        meaning="toward open directions in the 90° in front of the right side",
    ),
)
