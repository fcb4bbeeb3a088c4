"""Short names of the behaviours, as every view of them writes them.

The terminal's tables and BACs in words (``lfdfuse segment``, ``estimate``, ``inspect``) and the
plots' legends (``lfdfuse plot``, the report) all abbreviate a behaviour the same way: by the
paper's Table I acronym from the catalogue (DESIGN §4), and an attractor by its target's name, as
the map labels it.

>>> [abbreviation(n) for n in ("avoid", "wall_attract_left", "attract_red", "my_own")]
['LA', 'WFL', 'red', 'my_own']
>>> legend_entry("wander_right")
'WR = wander_right'
"""

from __future__ import annotations

from lfdfuse.behaviors.catalogue import BASE_BEHAVIORS, abbreviation, spec_of

__all__ = ["ABBREVIATIONS", "abbreviation", "legend_entry"]

#: canonical behaviour name → the paper's Table I acronym
ABBREVIATIONS: dict[str, str] = {n: s.acronym for n in BASE_BEHAVIORS if (s := spec_of(n)) is not None}


def legend_entry(name: str) -> str:
    """``ABBREVIATION = name``: how a legend (terminal or plot) explains an abbreviation."""
    return f"{abbreviation(name)} = {name}"
