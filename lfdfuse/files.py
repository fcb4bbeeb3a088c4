"""Files at the edge: atomic output (temp file, fsync, rename) and the YAML files users hand us.

An interrupted or failed command leaves no half-written output behind; a YAML syntax error
names the file and line.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

import yaml

from lfdfuse.errors import ConfigError, LfdError


def umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically, with the usual permissions; errors as :class:`LfdError`."""
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise LfdError(f"cannot write {p}: folder {parent} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=parent)
    except OSError as exc:
        raise LfdError(f"cannot write {p}: {exc.strerror}") from exc
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~umask())
        os.replace(tmp, p)
    except OSError as exc:
        raise LfdError(f"cannot write {p}: {exc.strerror}") from exc
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


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
