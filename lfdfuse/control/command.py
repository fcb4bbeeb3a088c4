"""The vector ↔ command mapping (DESIGN §3). The only module that knows it.

A vector ``V`` in the robot frame becomes a command by its heading ``θ = atan2(V_y, V_x)``:
the turn rate is ``ω = clip(k·θ, ±ω_max)`` and the speed ``v = v_max·max(0, cos θ)`` falls
with ``|θ|`` (zero at ±90° and beyond). The inverse recovers ``θ`` from a command: from ``ω``
while it is below its limit, else from ``v`` (``|θ| = arccos(v / v_max)``). A command that
neither moves nor turns, or that reverses, carries no heading information.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class DriveParams:
    """Speed and turn limits of the robot (Pioneer 3DX-like)."""

    v_max_mps: float = 0.4
    omega_max_rps: float = math.radians(100.0)
    k_turn: float = 1.5  # 1/s: turn-rate gain on the heading error
    #: below these a command counts as standing still
    v_still_mps: float = 1e-3
    omega_still_rps: float = 1e-3


def heading_to_command(heading_rad: np.ndarray, p: DriveParams) -> tuple[np.ndarray, np.ndarray]:
    """Commands ``(v, ω)`` for headings ``(...)`` in radians (robot frame, wrapped to ±π)."""
    th = np.arctan2(np.sin(heading_rad), np.cos(heading_rad))
    omega = np.clip(p.k_turn * th, -p.omega_max_rps, p.omega_max_rps)
    v = p.v_max_mps * np.maximum(0.0, np.cos(th))
    return v, omega


def heading_command(heading_rad: float, p: DriveParams) -> tuple[float, float]:
    """:func:`heading_to_command` of one heading, as Python floats: the same numbers (numpy's
    sine, cosine and arc tangent, the clip and the floor as comparisons) without the array work.
    A heading the wrap leaves as it was (most: within ±π) has the cosine computed already."""
    cos_h = np.cos(heading_rad)
    th = float(np.arctan2(np.sin(heading_rad), cos_h))
    omega = p.k_turn * th
    if omega < -p.omega_max_rps:
        omega = -p.omega_max_rps
    elif omega > p.omega_max_rps:
        omega = p.omega_max_rps
    c = float(cos_h) if th == heading_rad else float(np.cos(th))  # ±0: the one cosine, 1
    return p.v_max_mps * (c if c > 0.0 or c != c else 0.0), omega


def vector_to_command(vx: np.ndarray, vy: np.ndarray, p: DriveParams) -> tuple[np.ndarray, np.ndarray]:
    """Commands ``(v, ω)`` for robot-frame vectors; a zero vector gives a stop."""
    vx = np.asarray(vx, dtype=np.float64)
    vy = np.asarray(vy, dtype=np.float64)
    v, omega = heading_to_command(np.arctan2(vy, vx), p)
    zero = (vx == 0.0) & (vy == 0.0)
    return np.where(zero, 0.0, v), np.where(zero, 0.0, omega)


def command_to_heading(v: np.ndarray, omega: np.ndarray, p: DriveParams) -> tuple[np.ndarray, np.ndarray]:
    """Inverse mapping: demonstrated headings ``θ`` (rad) and a mask of informative steps.

    ``v`` and ``omega`` have the same shape; the mask is False where the robot neither moves
    nor turns, or reverses (``v < 0``), or the command is not finite: no heading information.
    Speeds above ``v_max`` count as ``v_max``.
    """
    v = np.asarray(v, dtype=np.float64)
    omega = np.asarray(omega, dtype=np.float64)
    ratio = np.clip(v / p.v_max_mps, 0.0, 1.0)
    # A saturated turn, or a turn on the spot, says the heading is at least the saturation
    # angle; the speed tells how far past it (arccos(0) = 90° for a turn on the spot).
    by_speed = (np.abs(omega) >= p.omega_max_rps * (1.0 - 1e-9)) | (v <= p.v_still_mps)
    th_sat = p.omega_max_rps / p.k_turn
    from_v = np.sign(omega) * np.maximum(np.arccos(ratio), th_sat)
    theta = np.where(by_speed, from_v, omega / p.k_turn)
    moving = (np.abs(v) > p.v_still_mps) | (np.abs(omega) > p.omega_still_rps)
    # reversing carries no heading for primitives that steer a forward-moving robot (DESIGN §3)
    informative = moving & (v >= 0.0) & np.isfinite(v) & np.isfinite(omega)
    return theta, informative


def command_to_vector(v: np.ndarray, omega: np.ndarray, p: DriveParams) -> tuple[np.ndarray, np.ndarray]:
    """Demonstrated unit vectors ``(N, 2)`` and the informative-step mask ``(N,)``."""
    theta, ok = command_to_heading(v, omega, p)
    return np.stack([np.cos(theta), np.sin(theta)], axis=-1), ok
