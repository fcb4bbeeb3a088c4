"""The one error hierarchy of lfdfuse.

The CLI catches :class:`LfdError` only, prints ``error: <message>`` and exits 1. Any other
exception is a bug and keeps its traceback.
"""

from __future__ import annotations


class LfdError(Exception):
    """A user-facing error: bad input, missing file, invalid configuration."""


class WorldError(LfdError):
    """A world file or world name is invalid."""


class LogError(LfdError):
    """An MCAP log cannot be read or written."""


class ConfigError(LfdError):
    """A task, teacher, behaviour set or fusion table is invalid."""
