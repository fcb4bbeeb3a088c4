"""The JSON schemas embedded in every file: Foxglove's well-known ones and our own."""

from __future__ import annotations

import json
from functools import cache
from importlib import resources
from typing import Any


@cache
def schema_text(name: str) -> bytes:
    """The schema file for a schema name such as ``foxglove.LaserScan`` or ``lfdfuse.Twist``."""
    base = resources.files("lfdfuse") / "schemas"
    if name.startswith("foxglove."):
        path = base / "foxglove" / f"{name.split('.', 1)[1]}.json"
    else:
        path = base / f"{name}.json"
    return path.read_bytes()


def schema(name: str) -> dict[str, Any]:
    result: dict[str, Any] = json.loads(schema_text(name))
    return result
