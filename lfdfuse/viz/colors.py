"""Fixed colours: one per behaviour everywhere (bars, legends, reports), one per goal segment or step.

A behaviour keeps its colour in every figure, whatever the table's behaviour order; the left and
right variants of a primitive are two shades of one hue, so a reader sees the family first.
``attract_<target>`` takes its target's colour (red, green, blue, …), as the map draws it.
"""

from __future__ import annotations

import colorsys

from lfdfuse.behaviors import catalogue
from lfdfuse.behaviors.names import legend_entry

#: behaviour name → hex colour (the catalogue's: colour-blind-safe hues from the Okabe–Ito and
#: Tol palettes)
BEHAVIOR_COLORS: dict[str, str] = {n: catalogue.color(n) for n in catalogue.BASE_BEHAVIORS}

#: goal segments and network steps, in order: Tol's "bright" palette (without its grey, which
#: is the colour of a tick after the last goal), then his "dark" one; :func:`step_color` goes on
#: past them with hues of its own, so no two steps ever share a colour
STEP_COLORS: tuple[str, ...] = (
    "#4477AA",
    "#EE6677",
    "#228833",
    "#CCBB44",
    "#66CCEE",
    "#AA3377",
    "#222255",
    "#225555",
    "#663333",
    "#666633",
    "#225522",
)

WALL_COLOR = "#1a1a1a"
OBSTACLE_COLOR = "#8c5a2b"
PATH_COLOR = "#d62728"  # the paper draws the robot path in red (Fig. 5)
COLLISION_COLOR = "#d62728"
UNKNOWN_COLOR = catalogue.UNKNOWN_COLOR


def _hex(rgb: tuple[float, float, float]) -> str:
    return "#" + "".join(f"{round(255 * c):02x}" for c in rgb)


def target_color(name: str) -> str:
    """The colour a target is drawn in (its name's colour, else grey)."""
    return catalogue.target_color(name)


def behavior_color(name: str) -> str:
    """The fixed colour of a behaviour (the catalogue's); ``attract_<target>`` takes its target's."""
    return catalogue.color(name)


def behavior_hatch(name: str) -> str:
    """The hatch that tells a right variant from its left one in greyscale print ('' : none)."""
    return catalogue.hatch(name)


def behavior_label(name: str) -> str:
    """The legend label, ``WFL = wall_attract_left``: the abbreviation the terminal's tables use
    (:mod:`lfdfuse.behaviors.names`, the one table of them) and the name it stands for."""
    return legend_entry(name)


def step_color(index: int) -> str:
    """The colour of goal segment or network step ``index`` (from 0): :data:`STEP_COLORS`, then
    hues a golden angle apart at alternating lightness. Distinct for every index (a test draws
    hundreds), never the grey of ticks after the last goal."""
    if index < len(STEP_COLORS):
        return STEP_COLORS[index]
    k = index - len(STEP_COLORS)
    hue = (0.11 + k * 0.618033988749895) % 1.0
    light = (0.35, 0.5, 0.65)[k % 3]
    return _hex(colorsys.hls_to_rgb(hue, light, 0.75 - 0.1 * ((k // 3) % 3)))
