"""Progress of long work, as the library reports it: a ``(done, total)`` callback.

The library never draws a bar (the CLI does, ``rich.progress``); a long computation takes an
optional :data:`Progress` and calls it as the work goes, in any unit it likes (steps, seconds,
rows). A computation made of parts hands each part a slice of its own range with :func:`part`,
so every level reports in its own units and the caller still sees one fraction that only grows.

>>> seen = []
>>> sub = part(lambda d, t: seen.append(round(d / t, 2)), start=2.0, size=6.0, total=10.0)
>>> sub(0.0, 3.0); sub(1.5, 3.0); sub(3.0, 3.0)
>>> seen
[0.2, 0.5, 0.8]
>>> part(None, start=0.0, size=1.0, total=1.0) is None
True
"""

from __future__ import annotations

from collections.abc import Callable

#: ``(done, total)``: the share ``done / total`` of the work is done (any unit, ``total > 0``)
Progress = Callable[[float, float], None]


def part(progress: Progress | None, *, start: float, size: float, total: float) -> Progress | None:
    """The callback of a sub-task that is the work ``[start, start + size)`` out of ``total``:
    its own ``(done, of)`` reaches ``progress`` as ``(start + size · done / of, total)``.
    None when there is nobody to tell."""
    if progress is None:
        return None
    whole = max(total, 1e-12)

    def sub(done: float, of: float) -> None:
        share = min(1.0, max(0.0, done / of)) if of > 0 else 1.0
        progress(min(whole, start + size * share), whole)

    return sub


def tell(progress: Progress | None, done: float, total: float) -> None:
    """Call ``progress`` when there is one (``total`` at least a tiny positive number)."""
    if progress is not None:
        progress(done, max(total, 1e-12))
