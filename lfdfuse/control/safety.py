"""A reflex below any controller: do not drive into a laser return just ahead.

Both the scripted teacher (a person does not drive into walls) and the behaviour network (a
real robot's low-level stop) use it. A heading is *free* when no laser return lies in the strip
ahead of the robot along it, ``lookahead_m`` long and ``halfwidth_m`` to each side. The reflex
returns the free heading nearest the wanted one (within ±90°), or a turn on the spot toward it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lfdfuse.kernels.jit import Warmup, kernel


@dataclass(frozen=True)
class SafetyParams:
    lookahead_m: float = 0.7
    halfwidth_m: float = 0.32  # robot radius + margin
    step_deg: float = 5.0


def _blocked_loop(
    r: np.ndarray, cos_d: np.ndarray, sin_d: np.ndarray, lookahead: float, halfwidth: float
) -> bool:
    """Whether a return lies in the strip along the heading whose beam offsets have the cosines
    ``cos_d`` and sines ``sin_d``: the first test of :func:`free_heading_reference`, beam by beam."""
    for j in range(r.shape[0]):
        x = r[j]
        r1 = x if np.isfinite(x) and x > 0 else 0.0
        along = r1 * cos_d[j]
        if along > 0 and along < lookahead and abs(r1 * sin_d[j]) < halfwidth:
            return True
    return False


#: the common case of :func:`free_heading` (the wanted heading free) in one compiled pass
BLOCKED = kernel(_blocked_loop)
#: a short run (a few seconds simulated) tests its headings in numpy: numba would cost it more
_WARMUP = Warmup(1000)


def free_heading(
    rel_rad: float, ranges_m: np.ndarray, angles_rad: np.ndarray, p: SafetyParams = SafetyParams()
) -> float:
    """The free robot-frame heading nearest ``rel_rad`` (see the module docstring).

    The wanted heading's test runs compiled where it can (:data:`BLOCKED`: the cosines and sines
    numpy's, the same products and comparisons), and a blocked heading's candidates are then
    tested a block at a time (:func:`_nearest_free`); every test without numba is
    :func:`free_heading_reference`."""
    if (
        type(ranges_m) is np.ndarray
        and type(angles_rad) is np.ndarray
        and ranges_m.dtype == np.float64
        and angles_rad.dtype == np.float64
        and ranges_m.shape == angles_rad.shape
        and _WARMUP()
        and BLOCKED.ready()
    ):
        d1 = angles_rad - rel_rad
        if not BLOCKED(ranges_m, np.cos(d1), np.sin(d1), p.lookahead_m, p.halfwidth_m):
            return rel_rad
        return _nearest_free(rel_rad, ranges_m, angles_rad, p)
    return free_heading_reference(rel_rad, ranges_m, angles_rad, p)


#: candidate headings :func:`_nearest_free` tests at a time
_BLOCK = 8


def _nearest_free(rel_rad: float, ranges_m: np.ndarray, angles_rad: np.ndarray, p: SafetyParams) -> float:
    """:func:`free_heading_reference` of a blocked heading, its candidates tested a block at a
    time, nearest first, until one is free (the same arrays, row for row: the same numbers)."""
    r1, cands = _returns(ranges_m), _candidates(rel_rad, p)
    for lo in range(0, len(cands), _BLOCK):
        block = cands[lo : lo + _BLOCK]
        free = np.nonzero(~_blocked(r1, angles_rad, block, p))[0]
        if len(free):
            return float(block[free[0]])
    return _boxed_in(rel_rad)


def free_heading_reference(
    rel_rad: float, ranges_m: np.ndarray, angles_rad: np.ndarray, p: SafetyParams = SafetyParams()
) -> float:
    """:func:`free_heading` in numpy: the reference."""
    r1 = _returns(ranges_m)
    d1 = angles_rad - rel_rad
    along1 = r1 * np.cos(d1)
    if not ((along1 > 0) & (along1 < p.lookahead_m) & (np.abs(r1 * np.sin(d1)) < p.halfwidth_m)).any():
        return rel_rad  # the common case: the wanted heading is free
    cands = _candidates(rel_rad, p)
    free = np.nonzero(~_blocked(r1, angles_rad, cands, p))[0]
    if len(free) == 0:
        return _boxed_in(rel_rad)
    return float(cands[free[0]])


def _returns(ranges_m: np.ndarray) -> np.ndarray:
    """The ranges, with no return (inf, NaN, 0) as range 0, which no strip test accepts (along > 0)."""
    return np.where(np.isfinite(ranges_m) & (ranges_m > 0), ranges_m, 0.0)


def _candidates(rel_rad: float, p: SafetyParams) -> np.ndarray:
    """The headings tried, nearest first: ``rel_rad``, then every ``step_deg`` to 90° each way,
    the side of ``rel_rad`` first."""
    offsets = np.radians(np.arange(p.step_deg, 90.0 + 1e-9, p.step_deg))
    first, second = (-offsets, offsets) if rel_rad < 0 else (offsets, -offsets)
    return np.concatenate([[rel_rad], rel_rad + np.column_stack([first, second]).ravel()])


def _blocked(r1: np.ndarray, angles_rad: np.ndarray, cands: np.ndarray, p: SafetyParams) -> np.ndarray:
    """Per candidate heading, whether a return lies in its strip (``lookahead_m`` ahead,
    ``halfwidth_m`` to each side)."""
    diff = angles_rad[None, :] - cands[:, None]
    r = r1[None, :]
    along = r * np.cos(diff)
    lateral = np.abs(r * np.sin(diff))
    return np.asarray(((along > 0) & (along < p.lookahead_m) & (lateral < p.halfwidth_m)).any(axis=1))


def _boxed_in(rel_rad: float) -> float:
    """Every candidate blocked: turn hard, past 90°, toward ``rel_rad``'s side (left at 0)."""
    return math.copysign(math.pi / 2 + 0.3, rel_rad if rel_rad != 0.0 else 1.0)
