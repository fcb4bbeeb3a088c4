"""The command model of a segmented demo, its command set and its decisions (DESIGN §6).

``segment`` records which model a demo needs (metadata ``segment_commands``, see
:mod:`lfdfuse.segment.commands`); ``estimate --commands`` can force either. For the discrete
model this module finds, from the demonstrated headings alone (each command stands for one
heading under the drive mapping), the command set (:class:`~lfdfuse.estimate.model.CommandBins`),
the decision steps and the heading interval each step observes (its command's bin, or at a nudge
the interval between two commands): see :mod:`lfdfuse.estimate.model` for the model itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.model import CommandBins
from lfdfuse.segment.commands import COMMAND_MODES, FEW_COMMANDS
from lfdfuse.segment.read import SegmentedRun

#: two demonstrated headings closer than this are the same command
SAME_HEADING_RAD = 1e-6


@dataclass(frozen=True)
class Commands:
    """A demo's command model; for ``discrete`` its command set, decision steps ``(N,)`` and the
    heading interval each step observes ``bounds (N, 2)`` (rad, see :func:`observed_bounds`)."""

    mode: Literal["continuous", "discrete"]
    bins: CommandBins | None = None
    decisions: np.ndarray | None = None  # steps where the person decided (informative or not)
    bounds: np.ndarray | None = None


def headings_of(run: SegmentedRun) -> np.ndarray:
    """The demonstrated heading (rad) of every step."""
    return np.asarray(np.arctan2(run.demo[:, 1], run.demo[:, 0]))


def decision_steps(run: SegmentedRun, *, recheck_s: float | None) -> np.ndarray:
    """Steps where the held command changes, or (with ``recheck_s``) is held that long again.

    A change of informativeness (a stop, a reverse, moving again) is a change of command. The
    result depends only on the command held at each scan, not on how often the log repeated it.
    """
    n = len(run.t_ns)
    out = np.zeros(n, dtype=bool)
    if n == 0:
        return out
    h = headings_of(run)
    inf = run.informative
    changed = np.ones(n, dtype=bool)
    changed[1:] = (inf[1:] != inf[:-1]) | (inf[1:] & (np.abs(h[1:] - h[:-1]) > SAME_HEADING_RAD))
    if recheck_s is None:
        return changed
    every = int(round(recheck_s * 1e9))
    t = run.t_ns.tolist()
    last = t[0]
    for i in range(n):
        if changed[i] or t[i] - last >= every:
            out[i] = True
            last = t[i]
    return out


def bins_of(run: SegmentedRun) -> CommandBins:
    """The command set: the distinct demonstrated headings of the informative steps and their
    mirror images (a keyboard or a teleop panel offers both sides: a person who only turned
    right still had the left keys, and not pressing them says the fused vector did not point
    that way)."""
    h = headings_of(run)[run.informative]
    if len(h) == 0:
        raise ConfigError("the demo has no informative command to learn from")
    return CommandBins.from_headings(np.unique(np.round(h, 9))).mirrored()


def observed_bounds(run: SegmentedRun, bins: CommandBins, *, nudge_s: float | None) -> np.ndarray:
    """The heading interval ``(N, 2)`` (rad, ``lo < hi``) each step's command says the person
    wanted: the bin of the held command, except at a *nudge*.

    A nudge is a press of command ``c`` away from ``c₀`` undone (``c₀`` pressed again) within
    ``nudge_s``: the person wanted a heading between the two and held ``c`` for part of the
    time (a tap of an arc key to correct a drift), so the press observes the interval between
    ``c₀``'s and ``c``'s headings instead of ``c``'s bin. A stop or a reverse on either side is no
    nudge. Steps without a heading keep the bin of their (meaningless) heading.
    """
    h = headings_of(run)
    out = bins.bounds_of(h)
    if nudge_s is None:
        return out
    inf = run.informative
    presses = np.nonzero(decision_steps(run, recheck_s=None))[0]
    within = int(round(nudge_s * 1e9))
    for before, press, back in zip(
        presses[:-2].tolist(), presses[1:-1].tolist(), presses[2:].tolist(), strict=True
    ):
        if not (inf[before] and inf[press] and inf[back]):
            continue
        if abs(h[back] - h[before]) > SAME_HEADING_RAD or run.t_ns[back] - run.t_ns[press] >= within:
            continue
        out[press] = sorted((h[before], h[press]))
    return out


def commands_of(
    run: SegmentedRun,
    *,
    requested: str = "auto",
    recheck_s: float | None = 1.0,
    nudge_s: float | None = 1.0,
) -> Commands:
    """The command model of ``run``: ``requested``, else what segment recorded, else detected."""
    if requested not in COMMAND_MODES:
        raise ConfigError(f"--commands must be one of {', '.join(COMMAND_MODES)}, got {requested!r}")
    mode = requested
    if mode == "auto":
        mode = run.metadata.get("segment_commands", "auto")
    if mode not in ("continuous", "discrete"):
        distinct = len(np.unique(np.round(headings_of(run)[run.informative], 9)))
        mode = "discrete" if distinct <= FEW_COMMANDS else "continuous"
    if mode == "continuous":
        return Commands("continuous")
    bins = bins_of(run)
    return Commands(
        "discrete",
        bins,
        decision_steps(run, recheck_s=recheck_s),
        observed_bounds(run, bins, nudge_s=nudge_s),
    )
