"""Reading the YAML files users hand us (tasks, fusion tables), with one-line errors."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from lfdfuse.errors import ConfigError


def parse_yaml(text: str, *, origin: str) -> Any:
    """YAML text into data; a syntax error names the file and line."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise ConfigError(f"{origin}: malformed YAML{where}") from exc


def read_yaml(path: str | Path, *, what: str) -> Any:
    """Read and parse a YAML file; ``what`` names it in errors ("task file", "fusion table")."""
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise ConfigError(f"cannot read {what} {p}: {exc.strerror}") from exc
    return parse_yaml(text, origin=str(p))
