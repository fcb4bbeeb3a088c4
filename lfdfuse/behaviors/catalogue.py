"""The catalogue of behaviour primitives: every :class:`~lfdfuse.behaviors.spec.BehaviorSpec`.

Gathered from the modules of :mod:`lfdfuse.behaviors.library` (each holds its ``SPECS``) and
ordered by rank. Everything else that lists behaviours reads it: the names a behaviour set may
use, the paper's acronyms, the colours of figures and of the ``/lfd/overlay`` arrows, the inputs
``drive`` checks the robot has, the default weights of a table; the fusion-table schema and
the Foxglove layouts are checked against it by a test.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Sequence

from lfdfuse.behaviors import library
from lfdfuse.behaviors.spec import ATTRACT, BehaviorSpec, Input, attract_target
from lfdfuse.errors import ConfigError
from lfdfuse.world.parse import TARGET_COLORS


def _gather() -> tuple[BehaviorSpec, ...]:
    specs: list[BehaviorSpec] = []
    for info in sorted(pkgutil.iter_modules(library.__path__), key=lambda m: m.name):
        module = importlib.import_module(f"{library.__name__}.{info.name}")
        specs.extend(getattr(module, "SPECS", ()))
    specs.sort(key=lambda s: s.rank)
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise ConfigError(f"the behaviour catalogue names a behaviour twice: {', '.join(names)}")
    return tuple(specs)


#: every spec, by rank
CATALOGUE: tuple[BehaviorSpec, ...] = _gather()

#: the behaviours that are one name each (not a family such as ``attract_<target>``), by rank
BASE_BEHAVIORS: tuple[str, ...] = tuple(s.name for s in CATALOGUE if not s.family)

#: the family of behaviours toward a target
ATTRACT_SPEC: BehaviorSpec = next(s for s in CATALOGUE if s.family and s.name == ATTRACT)

#: grey for a name the catalogue does not know
UNKNOWN_COLOR = "#7f7f7f"


def spec_of(name: str) -> BehaviorSpec | None:
    """The spec of behaviour ``name`` (a family member's is its family's), None when unknown."""
    for s in CATALOGUE:
        if s.names(name):
            return s
    return None


def abbreviation(name: str) -> str:
    """The short name of a behaviour: its acronym, an attractor's target, else the name itself."""
    target = attract_target(name)
    if target is not None:
        return target
    s = spec_of(name)
    return s.acronym if s is not None else name


def _hex(rgb: tuple[float, float, float]) -> str:
    return "#" + "".join(f"{round(255 * c):02x}" for c in rgb)


def target_color(name: str) -> str:
    """The colour a target is drawn in (its name's colour, else grey)."""
    return _hex(TARGET_COLORS.get(name, (0.6, 0.6, 0.6)))


def color(name: str) -> str:
    """The fixed ``#rrggbb`` colour of a behaviour; ``attract_<target>`` takes its target's."""
    target = attract_target(name)
    if target is not None:
        return target_color(target)
    s = spec_of(name)
    return s.color if s is not None and s.color else UNKNOWN_COLOR


def rgb(name: str) -> tuple[float, float, float]:
    """:func:`color` as (r, g, b) in [0, 1]."""
    h = color(name).lstrip("#")
    return (int(h[0:2], 16) / 255, int(h[2:4], 16) / 255, int(h[4:6], 16) / 255)


def hatch(name: str) -> str:
    s = spec_of(name)
    return s.hatch if s is not None else ""


def needs(name: str) -> frozenset[Input]:
    """The inputs behaviour ``name`` needs (an unknown name: the laser)."""
    s = spec_of(name)
    return s.inputs if s is not None else frozenset({"laser"})


def default_weights_for(behaviors: list[str] | tuple[str, ...]) -> dict[str, float]:
    """Safe wandering for BACs never seen in training: each behaviour's default role.

    The fixed ones first (``avoid`` 1, ``sonar_avoid`` 0.5), then the wanderers sharing 1
    equally; a set with none of them weighs every behaviour 1.
    """
    present = [s for s in CATALOGUE if not s.family and s.name in behaviors]
    w: dict[str, float] = {s.name: s.default_weight for s in present if s.default_role == "fixed"}
    sharing = [s.name for s in present if s.default_role == "share"]
    for b in sharing:
        w[b] = round(1.0 / len(sharing), 4)
    if not w:
        w = {b: 1.0 for b in behaviors}
    return w


def safe_default(weights: dict[str, float], behaviors: Sequence[str]) -> dict[str, float]:
    """Weights for BACs never seen in training made safe: the fixed behaviours (``avoid``,
    ``sonar_avoid``) weigh at least their default role's weight (the others as they were).

    A step's default fit to the teacher's heading leaves ``avoid`` near 0 (the teacher seldom
    needed it), and a BAC never seen in training is most often a robot where the teacher never
    drove, near a wall.
    """
    out = dict(weights)
    for s in CATALOGUE:
        if not s.family and s.default_role == "fixed" and s.name in behaviors:
            out[s.name] = max(out.get(s.name, 0.0), s.default_weight)
    return out


def name_pattern() -> str:
    """The regular expression of a valid behaviour name (the fusion-table schema's)."""
    alts = [*BASE_BEHAVIORS, *(f"{s.name}[A-Za-z0-9_]+" for s in CATALOGUE if s.family)]
    return "^(" + "|".join(alts) + ")$"
