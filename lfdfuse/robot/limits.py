"""The robot's speed and turn-rate limits as a provenance states them.

``import`` writes ``v_max_mps`` and ``omega_max_rps`` into a log's metadata (an imported robot's
own limits); ``estimate`` carries them into a table's ``estimated_by``. ``segment`` reads them
from the log to map commands to headings, ``drive`` from the table to clamp what it sends.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

LIMIT_KEYS = ("v_max_mps", "omega_max_rps")


def stated_limits(provenance: Mapping[str, object]) -> tuple[float | None, float | None]:
    """The speed (m/s) and turn-rate (rad/s) limits ``provenance`` states; None for a limit it
    does not state, or states as anything but a positive finite number.

    >>> stated_limits({"v_max_mps": "0.3", "omega_max_rps": "inf"})
    (0.3, None)
    """
    out: list[float | None] = []
    for key in LIMIT_KEYS:
        raw = provenance.get(key)
        try:
            value = float(raw) if isinstance(raw, int | float | str) else math.nan
        except ValueError:
            value = math.nan
        out.append(value if math.isfinite(value) and value > 0 else None)
    return out[0], out[1]
