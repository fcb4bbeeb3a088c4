"""Off-route worlds, generated from a seed: a corridor ring with a dead-end spur.

The three-goal task (red, then green, then blue) is demonstrated once in such a world; green
sits at the end of a dead-end spur off the ring, out of the camera's view from the ring, so a
learned network reaches it only by turning off where the teacher did. What varies, drawn from
the seed (:func:`offroute_spec`): the ring's size, the corridor width, the leg the spur leaves
from, its side (left = into the ring, right = out of it, for a robot driving the ring
anticlockwise as the teacher does), its position along the leg and its length, and the number
of side openings (shorter dead ends, on either side) met between red and the spur. Red lies
ahead of the start on the south corridor; blue on the leg after the spur's, so the teacher
drives on round the ring after green.

Seeds are split once and for all (:data:`TUNING_SEEDS`, :data:`HELD_APART_SEEDS`): landmarks
are developed on the first range, and completion is reported on the second, never tuned on.

:func:`offroute_world` turns a spec into world data (the mapping a world YAML holds);
:func:`generate_offroute` parses it into a :class:`World`. ``python -m tests.support.generated_worlds
SEED`` prints a world's YAML (``lfdfuse simulate --world`` reads it from a file).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Any

import numpy as np
import yaml
from shapely.geometry import box

from lfdfuse.world.build import Rect, walls_of
from lfdfuse.world.parse import World, parse_world

#: seeds the landmarks are developed on …
TUNING_SEEDS = range(0, 1000)
#: … and seeds kept apart from them: completion is reported here, never tuned on
HELD_APART_SEEDS = range(1000, 2000)
#: … of which the first 160 were looked at world by world while the landmarks and the learned
#: steps were developed: the bench reports the held-apart seeds after them
DEVELOPED_SEEDS = HELD_APART_SEEDS[:160]
BENCH_SEEDS = HELD_APART_SEEDS[len(DEVELOPED_SEEDS) :]

#: the ring's legs in the order the teacher drives them (anticlockwise)
LEGS = ("south", "east", "north", "west")
SIDES = ("left", "right")


@dataclass(frozen=True)
class SideOpening:
    """A dead end off a ring leg: ``at_m`` along the leg (from the corner it is entered at,
    driving anticlockwise) to its centre line, ``length_m`` deep, ``width_m`` wide."""

    leg: str
    side: str
    at_m: float
    length_m: float
    width_m: float


@dataclass(frozen=True)
class OffRouteSpec:
    """One generated world: a ``size_m`` (x, y) ring of ``width_m`` corridors with a spur."""

    seed: int
    size_m: tuple[float, float]
    width_m: float
    start_at_m: float  # along the south leg, heading east
    red_at_m: float  # along the south leg
    spur: SideOpening  # green at its end
    decoys: tuple[SideOpening, ...]  # side openings between red and the spur, in route order
    blue_leg: str
    blue_at_m: float

    @property
    def name(self) -> str:
        return f"offroute-{self.seed}"


def _leg_frame(leg: str, size: tuple[float, float], w: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Origin (the leg's centre line at the corner it is entered at), direction and left normal."""
    sx, sy = size
    frames = {
        "south": ((0.0, w / 2), (1.0, 0.0)),
        "east": ((sx - w / 2, 0.0), (0.0, 1.0)),
        "north": ((sx, sy - w / 2), (-1.0, 0.0)),
        "west": ((w / 2, sy), (0.0, -1.0)),
    }
    o, d = (np.asarray(v) for v in frames[leg])
    return o, d, np.array([-d[1], d[0]])


def leg_point(
    leg: str, at_m: float, lateral_m: float, size: tuple[float, float], w: float
) -> tuple[float, float]:
    """The point ``at_m`` along a leg and ``lateral_m`` to its left (m) of the centre line."""
    o, d, n = _leg_frame(leg, size, w)
    p = o + at_m * d + lateral_m * n
    return float(p[0]), float(p[1])


def leg_length(leg: str, size: tuple[float, float]) -> float:
    return size[0] if leg in ("south", "north") else size[1]


def _rect(op: SideOpening, size: tuple[float, float], w: float) -> Rect:
    """The dead end's free rectangle, from the corridor's centre line (so the two overlap, however
    the coordinates round) to its end."""
    sgn = 1.0 if op.side == "left" else -1.0
    a = leg_point(op.leg, op.at_m - op.width_m / 2, 0.0, size, w)
    b = leg_point(op.leg, op.at_m + op.width_m / 2, sgn * (w / 2 + op.length_m), size, w)
    return (min(a[0], b[0]), min(a[1], b[1]), max(a[0], b[0]), max(a[1], b[1]))


def _fits(op: SideOpening, placed: list[SideOpening], size: tuple[float, float], w: float) -> bool:
    """A dead end clear of the other legs (corners, and the far side of the ring) and of the
    other dead ends, by a margin of wall."""
    margin = 1.5
    r = box(*_rect(op, size, w)).difference(box(*_ring_legs(size, w)[LEGS.index(op.leg)]))
    others = [box(*rect) for leg, rect in zip(LEGS, _ring_legs(size, w), strict=True) if leg != op.leg]
    return all(r.distance(o) >= margin for o in others) and all(
        r.distance(box(*_rect(p, size, w))) >= margin for p in placed
    )


def _ring_legs(size: tuple[float, float], w: float) -> list[Rect]:
    """The legs' rectangles in :data:`LEGS` order."""
    sx, sy = size
    return [(0, 0, sx, w), (sx - w, 0, sx, sy), (0, sy - w, sx, sy), (0, 0, w, sy)]


def _r(v: float) -> float:
    return round(float(v), 2)


def _route_position(d_m: float, spec_legs: list[tuple[str, float, float]]) -> tuple[str, float] | None:
    """The leg and position of route distance ``d_m`` over ``(leg, from_m, to_m)`` pieces."""
    for leg, a, b in spec_legs:
        if d_m <= b - a:
            return leg, a + d_m
        d_m -= b - a
    return None


def offroute_spec(seed: int) -> OffRouteSpec:
    """Draw a world's parameters from ``seed`` (the same seed, the same world)."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 21]))
    while True:
        w = _r(rng.uniform(2.0, 2.8))
        size = (_r(rng.uniform(28.0, 44.0)), _r(rng.uniform(18.0, 28.0)))
        start_at = _r(rng.uniform(0.2, 0.3) * size[0])
        red_at = _r(start_at + rng.uniform(5.0, 9.0))
        leg = str(rng.choice(["east", "north"]))
        side = str(rng.choice(SIDES))
        # on the north leg the spur lies before red's x, so the way there is anticlockwise
        hi = leg_length(leg, size) - w - 2.5 if leg == "east" else min(0.55 * size[0], red_at - 3.0)
        lo = w + 2.5
        if hi <= lo:
            continue
        spur = SideOpening(leg, side, _r(rng.uniform(lo, hi)), _r(rng.uniform(4.0, 9.0)), w)
        if not _fits(spur, [], size, w):
            continue
        # the route from red to the spur, leg by leg: where the side openings may be
        route = [("south", red_at + 2.0, size[0])]
        if leg == "north":
            route.append(("east", 0.0, size[1]))
        route.append((leg, 0.0, spur.at_m - spur.width_m / 2))
        total = sum(b - a for _, a, b in route)
        decoys: list[SideOpening] = []
        for _ in range(int(rng.integers(0, 4))):
            for _try in range(50):
                where = _route_position(float(rng.uniform(0.0, total)), route)
                if where is None:
                    continue
                op = SideOpening(
                    where[0],
                    str(rng.choice(SIDES)),
                    _r(where[1]),
                    _r(rng.uniform(3.0, 8.0)),
                    _r(rng.uniform(1.6, w)),
                )
                if _fits(op, [*decoys, spur], size, w):
                    decoys.append(op)
                    break
        order = {name: i for i, name in enumerate(LEGS)}
        decoys.sort(key=lambda o: (order[o.leg], o.at_m))
        blue_leg = LEGS[(order[leg] + 1) % len(LEGS)]
        blue_at = _r(rng.uniform(0.3, 0.7) * leg_length(blue_leg, size))
        return OffRouteSpec(seed, size, w, start_at, red_at, spur, tuple(decoys), blue_leg, blue_at)


def offroute_world(spec: OffRouteSpec) -> dict[str, Any]:
    """The world data (a world YAML's mapping) of ``spec``."""
    size, w = spec.size_m, spec.width_m
    rects = [*_ring_legs(size, w), *(_rect(o, size, w) for o in (spec.spur, *spec.decoys))]
    sgn = 1.0 if spec.spur.side == "left" else -1.0
    green = leg_point(spec.spur.leg, spec.spur.at_m, sgn * (w / 2 + spec.spur.length_m - 0.8), size, w)
    targets = {
        "red": leg_point("south", spec.red_at_m, 0.0, size, w),
        "green": green,
        "blue": leg_point(spec.blue_leg, spec.blue_at_m, 0.0, size, w),
    }
    start = leg_point("south", spec.start_at_m, 0.0, size, w)
    s = spec.spur
    return {
        "name": spec.name,
        "description": (
            f"generated off-route world (seed {spec.seed}): {size[0]:g} x {size[1]:g} m ring of "
            f"{w:g} m corridors, a {s.length_m:g} m dead-end spur on the {s.side} of the {s.leg} "
            f"corridor, {len(spec.decoys)} side opening(s) before it"
        ),
        "walls": walls_of(rects),
        "targets": [{"name": k, "position": [_r(x), _r(y)], "radius": 0.25} for k, (x, y) in targets.items()],
        "start": [_r(start[0]), _r(start[1]), 0.0],
    }


def generate_offroute(seed: int) -> World:
    """The off-route world of ``seed``, parsed (its YAML text attached as the source)."""
    data = offroute_world(offroute_spec(seed))
    text = yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=200)
    return parse_world(data, source=text, origin=data["name"])


def main(argv: list[str]) -> int:
    """Print the world of ``SEED`` as YAML, to look at or to hand to ``lfdfuse simulate --world``."""
    if len(argv) != 1 or not argv[0].isdigit():
        print("usage: python -m tests.support.generated_worlds SEED", file=sys.stderr)
        return 1
    print(generate_offroute(int(argv[0])).source, end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
