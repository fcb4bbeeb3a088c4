"""Which command model a demo needs (DESIGN §6): ``continuous`` or ``discrete``.

A scripted teacher's commands lie on the drive mapping and take thousands of values; a person at
a keyboard or at Foxglove's Teleop panel holds a few commands. ``auto`` reads the log: an imported
log states the structure of its commands (provenance ``command_model``, by
:func:`lfdfuse.robot.commands.classify_commands`: a few values held, or many changing smoothly)
and that is taken; otherwise a demo whose commands take at most :data:`FEW_COMMANDS` distinct
values is discrete, and so is one that a person drove (provenance ``teacher: human`` or
``keyboard:…``, or a ``/teleop/input`` channel) with at most :data:`PERSON_COMMANDS` values
(speed scaling keys multiply a keyboard's set).

>>> detect_commands(np.array([0.4, 0.4, 0.0]), np.array([0.0, 1.0, 1.0]), {}, ())
'discrete'
>>> detect_commands(np.linspace(0, 0.4, 50), np.linspace(-1, 1, 50), {}, ())
'continuous'
>>> detect_commands(np.array([0.1] * 22), np.linspace(0, 0.5, 22), {"command_model": "continuous", "teacher": "human"}, ())
'continuous'
"""

from __future__ import annotations

from enum import StrEnum
from typing import Literal

import numpy as np

from lfdfuse.errors import ConfigError

CommandMode = Literal["auto", "continuous", "discrete"]


class CommandChoice(StrEnum):
    """``--commands``: how the teacher commands (DESIGN §6)."""

    AUTO = "auto"  # from the log: import's command_model, provenance, /teleop/input, distinct commands
    CONTINUOUS = "continuous"  # on the drive mapping (a scripted teacher, a joystick)
    DISCRETE = "discrete"  # a few commands, held (a keyboard, Foxglove's Teleop panel)

    @property
    def mode(self) -> CommandMode:
        """The name the segment and estimate libraries take."""
        return self.value


COMMAND_MODES: tuple[str, ...] = tuple(c.value for c in CommandChoice)

#: so few distinct commands make any log discrete
FEW_COMMANDS = 12
#: a log a person drove is discrete up to this many distinct commands
PERSON_COMMANDS = 40
#: commands equal to this resolution (m/s, rad/s) are the same command
RESOLUTION = 1e-3


def distinct_commands(v: np.ndarray, omega: np.ndarray) -> int:
    """How many distinct finite commands ``(v, ω)`` a log holds (to :data:`RESOLUTION`)."""
    ok = np.isfinite(v) & np.isfinite(omega)
    pairs = np.round(np.stack([v[ok], omega[ok]], axis=-1) / RESOLUTION).astype(np.int64)
    return int(len(np.unique(pairs, axis=0))) if len(pairs) else 0


def by_person(metadata: dict[str, str], topics: tuple[str, ...] | list[str]) -> bool:
    """Whether provenance or channels say a person drove (teleop, a keyboard, an import)."""
    teacher = metadata.get("teacher", "")
    return teacher == "human" or teacher.startswith("keyboard:") or "/teleop/input" in topics


def detect_commands(
    v: np.ndarray,
    omega: np.ndarray,
    metadata: dict[str, str],
    topics: tuple[str, ...] | list[str],
    requested: str = "auto",
) -> Literal["continuous", "discrete"]:
    """The command model of a log's commands ``v, ω (M,)``: ``requested`` unless ``auto``."""
    if requested not in COMMAND_MODES:
        raise ConfigError(f"--commands must be one of {', '.join(COMMAND_MODES)}, got {requested!r}")
    if requested == "continuous":
        return "continuous"
    if requested == "discrete":
        return "discrete"
    stated = metadata.get("command_model")
    if stated == "continuous":
        return "continuous"
    if stated == "discrete":
        return "discrete"
    n = distinct_commands(v, omega)
    if n <= FEW_COMMANDS or (by_person(metadata, topics) and n <= PERSON_COMMANDS):
        return "discrete"
    return "continuous"
