"""Atomic file output: a temp file in the target's folder, then a rename.

An interrupted or failed command leaves no half-written output behind.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from lfdfuse.errors import LfdError


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
        os.chmod(tmp, 0o666 & ~umask())
        os.replace(tmp, p)
    except OSError as exc:
        raise LfdError(f"cannot write {p}: {exc.strerror}") from exc
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
