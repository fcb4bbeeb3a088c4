"""``lfdfuse``: the command line. Each command lives in its own module of this package."""

from __future__ import annotations

from lfdfuse.cli import estimate, execute, inspect, segment, simulate, worlds  # noqa: F401  (registers commands)
from lfdfuse.cli.app import app

__all__ = ["app", "main"]


def main() -> None:
    app()


if __name__ == "__main__":
    main()
