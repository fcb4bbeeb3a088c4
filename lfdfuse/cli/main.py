"""``lfdfuse``: the command line. Each command lives in its own module of this package."""

from __future__ import annotations

import sys
import warnings

# every command module registers itself on the app when imported (one line each)
from lfdfuse.cli import (
    drive,  # noqa: F401
    estimate,  # noqa: F401
    evaluate,  # noqa: F401
    execute,  # noqa: F401
    import_cmd,  # noqa: F401
    inspect,  # noqa: F401
    plot,  # noqa: F401
    record,  # noqa: F401
    report,  # noqa: F401
    segment,  # noqa: F401
    simulate,  # noqa: F401
    teleop,  # noqa: F401
    worlds,  # noqa: F401
)
from lfdfuse.cli.app import app, finish

finish(app)  # every command's help from its docstring, readable at any width

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
