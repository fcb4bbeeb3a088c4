"""Fixed colours: one per behaviour everywhere (bars, legends, reports), one per goal segment or step.

A behaviour keeps its colour in every figure, whatever the table's behaviour order; the left and
right variants of a primitive are two shades of one hue, so a reader sees the family first.
``attract_<target>`` takes its target's colour (red, green, blue, …), as the map draws it.
"""

from __future__ import annotations

from lfdfuse.world.model import TARGET_COLORS

#: behaviour name → hex colour (colour-blind-safe hues from the Okabe–Ito and Tol palettes)
BEHAVIOR_COLORS: dict[str, str] = {
    "avoid": "#444444",
    "sonar_avoid": "#999999",
    "wander": "#E69F00",
    "wander_left": "#E69F00",
    "wander_right": "#F5C85C",
    "wall_attract": "#0072B2",
    "wall_attract_left": "#0072B2",
    "wall_attract_right": "#56B4E9",
    "wall_side_left": "#009E73",
    "wall_side_right": "#6FD3B3",
    "circular_avoid_left": "#CC79A7",
    "circular_avoid_right": "#E8B5D2",
}

#: hatches tell a right variant from its left one in greyscale print
BEHAVIOR_HATCH: dict[str, str] = {
    "wander_right": "//",
    "wall_attract_right": "//",
    "wall_side_right": "//",
    "circular_avoid_right": "//",
}

#: short labels (the paper's Table I acronyms where it has one)
BEHAVIOR_LABELS: dict[str, str] = {
    "avoid": "LA avoid",
    "sonar_avoid": "SA sonar avoid",
    "wander": "W wander",
    "wander_left": "WL wander left",
    "wander_right": "WR wander right",
    "wall_attract": "WF wall attract",
    "wall_attract_left": "WFL wall attract left",
    "wall_attract_right": "WFR wall attract right",
    "wall_side_left": "WSL wall side left",
    "wall_side_right": "WSR wall side right",
    "circular_avoid_left": "CAL circular avoid left",
    "circular_avoid_right": "CAR circular avoid right",
}

#: goal segments and network steps, in order (Tol's "bright" palette without the target hues)
STEP_COLORS: tuple[str, ...] = ("#4477AA", "#EE6677", "#228833", "#CCBB44", "#66CCEE", "#AA3377", "#BBBBBB")

WALL_COLOR = "#1a1a1a"
OBSTACLE_COLOR = "#8c5a2b"
PATH_COLOR = "#d62728"  # the paper draws the robot path in red (Fig. 5)
COLLISION_COLOR = "#d62728"
UNKNOWN_COLOR = "#7f7f7f"


def _hex(rgb: tuple[float, float, float]) -> str:
    return "#" + "".join(f"{round(255 * c):02x}" for c in rgb)


def target_color(name: str) -> str:
    """The colour a target is drawn in (its name's colour, else grey)."""
    return _hex(TARGET_COLORS.get(name, (0.6, 0.6, 0.6)))


def behavior_color(name: str) -> str:
    """The fixed colour of a behaviour; ``attract_<target>`` takes its target's colour."""
    if name.startswith("attract_"):
        return target_color(name[len("attract_") :])
    return BEHAVIOR_COLORS.get(name, UNKNOWN_COLOR)


def behavior_hatch(name: str) -> str:
    return BEHAVIOR_HATCH.get(name, "")


def behavior_label(name: str) -> str:
    """The legend label: ``BA red attract`` for attractors, the Table I acronym for the rest."""
    if name.startswith("attract_"):
        return f"BA attract {name[len('attract_') :]}"
    return BEHAVIOR_LABELS.get(name, name)


def step_color(index: int) -> str:
    return STEP_COLORS[index % len(STEP_COLORS)]
