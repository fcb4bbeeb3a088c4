"""``lfdfuse``: the command line. Each command lives in its own module of this package."""

from __future__ import annotations

import sys
import warnings

# each command's module is imported when that command runs (lfdfuse.cli.app.COMMANDS)
from lfdfuse.cli.app import app

__all__ = ["app", "main"]


def show_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: object = None,
    line: str | None = None,
) -> None:
    """A warning as one line on stderr, ``warning: <message>`` (not Python's two-line report with
    a source path): e.g. a compiled kernel that could not compile, its numpy reference running."""
    sys.stderr.write(f"warning: {' '.join(str(message).split())}\n")


# the CLI's own warnings format, for every command (the console script runs `app` directly)
warnings.showwarning = show_warning


def main() -> None:
    app()


if __name__ == "__main__":
    main()
