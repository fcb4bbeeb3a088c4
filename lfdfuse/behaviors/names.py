"""Short names of the behaviours: the one table every view of them uses.

The terminal's tables and BACs in words (``lfdfuse segment``, ``estimate``, ``inspect``) and the
plots' legends (``lfdfuse plot``, the report) all abbreviate a behaviour the same way: by the
paper's Table I acronym (DESIGN §4), and an attractor by its target's name, as the map labels it.

>>> [abbreviation(n) for n in ("avoid", "wall_attract_left", "attract_red", "my_own")]
['LA', 'WFL', 'red', 'my_own']
>>> legend_entry("wander_right")
'WR = wander_right'
"""

from __future__ import annotations

from lfdfuse.behaviors.primitives import ATTRACT

#: canonical behaviour name → the paper's Table I acronym
ABBREVIATIONS: dict[str, str] = {
    "avoid": "LA",
    "sonar_avoid": "SA",
    "wander": "W",
    "wander_left": "WL",
    "wander_right": "WR",
    "wall_attract": "WF",
    "wall_attract_left": "WFL",
    "wall_attract_right": "WFR",
    "wall_side_left": "WSL",
    "wall_side_right": "WSR",
    "circular_avoid_left": "CAL",
    "circular_avoid_right": "CAR",
}


def abbreviation(name: str) -> str:
    """The short name of a behaviour: its acronym, an attractor's target, else the name itself."""
    if name.startswith(ATTRACT):
        return name[len(ATTRACT) :]
    return ABBREVIATIONS.get(name, name)


def legend_entry(name: str) -> str:
    """``ABBREVIATION = name``: how a legend (terminal or plot) explains an abbreviation."""
    return f"{abbreviation(name)} = {name}"
