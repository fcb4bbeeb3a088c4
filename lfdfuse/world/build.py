"""Generate the built-in world YAML files from corridor rectangles.

Each world's free space is a union of axis-aligned rectangles; its walls are the rings of that
union. Run ``python -m lfdfuse.world.build`` to rewrite the YAML files next to this module; a
test checks the shipped files equal what this code generates.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml
from shapely.geometry import Polygon, box
from shapely.ops import unary_union

Rect = tuple[float, float, float, float]


def walls_of(rects: list[Rect]) -> list[list[list[float]]]:
    free = unary_union([box(*r) for r in rects])
    assert isinstance(free, Polygon), "free space must be one connected polygon"
    free = free.simplify(0.0)
    rings = [free.exterior, *free.interiors]
    return [[[round(x, 3), round(y, 3)] for x, y in ring.coords] for ring in rings]


def corridor() -> dict[str, Any]:
    rects: list[Rect] = [(0, 0, 30, 2.4)]
    for x in (7.0, 19.0):  # doorways on the left (+y side when driving +x)
        rects.append((x, 2.4, x + 1.0, 3.0))
    for x in (12.0, 24.0):  # doorways on the right
        rects.append((x, -0.6, x + 1.0, 0.0))
    return {
        "name": "corridor",
        "description": "straight 30 m corridor, 2.4 m wide, with four doorways",
        "walls": walls_of(rects),
        "start": [1.0, 1.2, 0.0],
    }


def tee() -> dict[str, Any]:
    rects: list[Rect] = [(0, 8, 30, 10), (0, 0, 30, 4), (6, 4, 8, 8), (22, 4, 24, 8)]
    return {
        "name": "tee",
        "description": "upper 2 m corridor and wide 4 m lower corridor joined by two T-junctions (paper Fig. 4 right)",
        "walls": walls_of(rects),
        "start": [1.0, 9.0, 0.0],
    }


def building() -> dict[str, Any]:
    w = 2.4
    rects: list[Rect] = [
        (0, 0, 40, w),  # south corridor
        (0, 30 - w, 40, 30),  # north corridor
        (0, 0, w, 30),  # west corridor
        (40 - w, 0, 40, 30),  # east corridor
        (w, 13.8, 40 - w, 16.2),  # cross corridor: T-junctions on west and east
        (18.8, w, 21.2, 30 - w),  # middle corridor: T-junctions on south and north, a crossing
    ]
    return {
        "name": "building",
        "description": "40 x 30 m floor loop, a cross and a middle corridor (T, rotated-T junctions, a crossing), red, green, blue targets (paper Figs. 4 left, 8)",
        "walls": walls_of(rects),
        "targets": [
            # the paper's first physical task: keep left to red (first left turn), centre to
            # green (straight over the crossing), keep right to blue (right at the T, right corner)
            {"name": "red", "position": [20.0, 8.0], "radius": 0.25},
            {"name": "green", "position": [20.0, 22.0], "radius": 0.25},
            {"name": "blue", "position": [38.8, 24.0], "radius": 0.25},
        ],
        "start": [4.0, 1.2, 0.0],
    }


def obstacles() -> dict[str, Any]:
    return {
        "name": "obstacles",
        "description": "20 x 3 m corridor with three obstacles on its centre line and a blocked end (paper Fig. 15)",
        "walls": walls_of([(0, 0, 20, 3)]),
        "obstacles": [{"circle": [x, 1.5, 0.3]} for x in (5.0, 10.0, 15.0)],
        "start": [1.0, 1.5, 0.0],
    }


def ring_spur() -> dict[str, Any]:
    w = 2.4
    rects: list[Rect] = [
        (0, 0, 32, w),  # south corridor
        (0, 22 - w, 32, 22),  # north corridor
        (0, 0, w, 22),  # west corridor
        (32 - w, 0, 32, 22),  # east corridor
        (21, 22 - w - 7, 21 + w, 22 - w),  # a dead-end spur, 7 m deep, south off the north corridor
    ]
    return {
        "name": "ring-spur",
        "description": "32 x 22 m corridor ring with a 7 m dead-end spur off the north corridor; green at its end, out of camera view from the ring (goals off the style's route)",
        "walls": walls_of(rects),
        "targets": [
            {"name": "red", "position": [14.0, 1.2], "radius": 0.25},
            {"name": "green", "position": [22.2, 13.4], "radius": 0.25},
            {"name": "blue", "position": [1.2, 9.0], "radius": 0.25},
        ],
        "start": [8.5, 1.2, 0.0],
    }


def ring_spur_large() -> dict[str, Any]:
    w = 2.6
    rects: list[Rect] = [
        (0, 0, 44, w),
        (0, 28 - w, 44, 28),
        (0, 0, w, 28),
        (44 - w, 0, 44, 28),
        (29, 28 - w - 8, 29 + w, 28 - w),  # the spur: same topology, other lengths
    ]
    return {
        "name": "ring-spur-large",
        "description": "ring-spur's topology at another scale: 44 x 28 m ring, 2.6 m corridors, an 8 m spur farther along (transfer of learned turn-offs)",
        "walls": walls_of(rects),
        "targets": [
            {"name": "red", "position": [20.0, 1.3], "radius": 0.25},
            {"name": "green", "position": [30.3, 18.2], "radius": 0.25},
            {"name": "blue", "position": [1.3, 12.0], "radius": 0.25},
        ],
        "start": [14.0, 1.3, 0.0],
    }


def office_room() -> dict[str, Any]:
    w = 2.4
    rects: list[Rect] = [
        (0, 0, 40, w),  # south corridor
        (0, 14 - w, 40, 14),  # north corridor
        (0, 0, w, 14),  # west corridor
        (40 - w, 0, 40, 14),  # east corridor
        (12, -4.5, 17, -0.3),  # office A (empty), below the south corridor
        (13.5, -0.3, 15.5, 0),  # its 2 m door
        (24, -4.5, 29, -0.3),  # office B: green behind the wall beside its door
        (26, -0.3, 28, 0),
    ]
    return {
        "name": "office-room",
        "description": "40 x 14 m corridor loop with two offices off the south corridor; green in the second, hidden beside its door (goals off the style's route)",
        "walls": walls_of(rects),
        "targets": [
            {"name": "red", "position": [8.0, 1.2], "radius": 0.25},
            {"name": "green", "position": [25.3, -3.0], "radius": 0.25},
            {"name": "blue", "position": [38.8, 8.0], "radius": 0.25},
        ],
        "start": [3.5, 1.2, 0.0],
    }


WORLDS = {
    "corridor": corridor,
    "tee": tee,
    "building": building,
    "obstacles": obstacles,
    "ring-spur": ring_spur,
    "ring-spur-large": ring_spur_large,
    "office-room": office_room,
}


def render(name: str) -> str:
    header = "# Generated by `python -m lfdfuse.world.build`; do not edit by hand.\n"
    return header + yaml.safe_dump(WORLDS[name](), sort_keys=False, default_flow_style=None, width=200)


def main() -> None:
    here = Path(__file__).parent / "builtin"
    for name in WORLDS:
        (here / f"{name}.yaml").write_text(render(name))


if __name__ == "__main__":
    main()
