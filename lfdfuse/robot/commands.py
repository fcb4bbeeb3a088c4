"""What a command stream is made of: a few values held (a keyboard) or many values changing
smoothly (a joystick, a proportional controller), and the robot's limits it shows.

Both are read from the structure of the commands, not their count alone: a person at a keyboard
sends a few levels per axis (a speed, a turn rate, their negatives, zero), each held until the next
key; a proportional wall follower sends 20 values of ω in 60 commands, each a small step from the
last; a gamepad a hundred. ``import`` prints the result and records it (``command_model``);
``segment --commands auto`` may use it for a log that states none.

>>> t = np.arange(6) * 500_000_000
>>> classify_commands(t, np.array([0.5, 0.5, 0.0, 0.0, 0.5, 0.0]), np.array([0.0, 1.0, 1.0, -1.0, 0.0, 0.0])).model
'discrete'
>>> w = 0.4 * np.sin(np.linspace(0, 3, 60))
>>> classify_commands(np.arange(60) * 100_000_000, np.full(60, 0.1), w).model
'continuous'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

#: commands equal to this resolution (m/s, rad/s) are the same command
RESOLUTION = 1e-3
#: at most this many distinct nonzero magnitudes on each axis: a few values (keys, bang-bang)
FEW_LEVELS = 4
#: a change smaller than this share of the axis's range is a smooth step (a continuous command)
SMOOTH_STEP = 0.25
#: the limit is anchored on this percentile of the nonzero magnitudes (``lower``: a value that occurs)
LIMIT_PERCENTILE = 99.0
#: a magnitude more than this many times the anchor is a wild command, never the limit
WILD_FACTOR = 2.0

CommandModel = Literal["continuous", "discrete"]


@dataclass(frozen=True)
class CommandStructure:
    """A command stream's structure: ``model``, how many distinct commands, the most distinct
    nonzero magnitudes on one axis, the median step of a change as a share of the axis's range,
    and the median time a value is held (s)."""

    model: CommandModel
    distinct: int
    levels: int
    step: float
    hold_s: float

    def describe(self) -> str:
        """One line for a summary: the model and why."""
        why = (
            f"{self.levels} level{'s' if self.levels != 1 else ''} per axis"
            if self.levels <= FEW_LEVELS
            else f"{self.levels} levels per axis, median step {100 * self.step:.0f}% of the range"
        )
        return f"{self.model} ({self.distinct} distinct commands, {why}, held {self.hold_s:.2g} s median)"


def classify_commands(t_ns: np.ndarray, v: np.ndarray, omega: np.ndarray) -> CommandStructure:
    """The structure of commands ``(t_ns, v, ω) (M,)`` sorted by time, each held until the next.

    ``discrete`` when every axis takes at most :data:`FEW_LEVELS` distinct nonzero magnitudes, or
    when the values jump: the median change is at least :data:`SMOOTH_STEP` of its axis's range
    (a keyboard with speed keys). ``continuous`` otherwise: many values, changing in small steps.
    No commands: ``discrete`` with zero of everything.
    """
    ok = np.isfinite(v) & np.isfinite(omega)
    t = np.asarray(t_ns, dtype=np.int64)[ok]
    q = np.round(np.stack([np.asarray(v)[ok], np.asarray(omega)[ok]], axis=-1) / RESOLUTION).astype(np.int64)
    if len(q) == 0:
        return CommandStructure("discrete", 0, 0, 0.0, 0.0)
    distinct = int(len(np.unique(q, axis=0)))
    levels = max(len(np.unique(np.abs(a[a != 0]))) for a in q.T)
    changed = np.nonzero(np.any(q[1:] != q[:-1], axis=1))[0] + 1
    starts = np.concatenate([[0], changed])
    hold = np.diff(t[starts]).astype(np.float64) / 1e9
    hold_s = float(np.median(hold)) if len(hold) else float(t[-1] - t[0]) / 1e9
    steps: list[float] = []
    for a in q.T:
        span = float(a.max() - a.min())
        moved = np.abs(np.diff(a))[changed - 1]
        steps += (moved[moved > 0] / span).tolist() if span > 0 else []
    step = float(np.median(steps)) if steps else 1.0
    model: CommandModel = "discrete" if levels <= FEW_LEVELS or step >= SMOOTH_STEP else "continuous"
    return CommandStructure(model, distinct, int(levels), step, hold_s)


def percentile_limit(values: np.ndarray) -> float | None:
    """A robot limit (speed or turn rate) from what it commanded: the largest nonzero magnitude
    that is plausible beside the :data:`LIMIT_PERCENTILE` percentile of them all (at most
    :data:`WILD_FACTOR` times it). Never the most common value (a person follower that mostly
    turned at 0.1 rad/s and at most 1.8 gets 1.8), never one wild command (19.9 m/s among 0.3).
    The largest magnitude when all are zero; None when there are none.

    >>> percentile_limit(np.array([0.3] * 30 + [0.0] * 10 + [19.9]))
    0.3
    >>> percentile_limit(np.array([0.1] * 165 + list(np.linspace(0.2, 1.5, 400)) + [1.8]))
    1.8
    """
    a = np.abs(np.asarray(values, dtype=np.float64))
    a = a[np.isfinite(a)]
    if len(a) == 0:
        return None
    moving = a[a > RESOLUTION]
    if len(moving) == 0:
        return float(a.max())
    anchor = float(np.percentile(moving, LIMIT_PERCENTILE, method="lower"))
    return round(float(moving[moving <= WILD_FACTOR * anchor].max()), 6)
