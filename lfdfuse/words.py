"""Counted nouns for the summaries every stage prints or writes: ``1 collision``, ``2 collisions``.

>>> counted(1, "collision"), counted(2, "collision"), counted(0, "goal reached", "goals reached")
('1 collision', '2 collisions', '0 goals reached')
"""

from __future__ import annotations


def counted(n: int, noun: str, plural: str | None = None) -> str:
    """``n`` and the noun, singular for exactly one (``plural`` defaults to the noun + ``s``)."""
    return f"{n} {noun if n == 1 else plural or noun + 's'}"
