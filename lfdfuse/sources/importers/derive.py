"""Commands derived from successive poses, for logs that recorded none (or ``--cmd-from odom``).

Between poses ``k`` and ``k+1`` the robot drove ``v = forward displacement / dt`` (the
displacement taken in the robot frame at the mid heading) and turned ``ω = Δyaw / dt``; the
command is stamped at pose ``k`` and held until the next. A light ``[1, 2, 1] / 4`` smoothing
takes the edge off odometry jitter without moving a turn's start by more than one pose.
"""

from __future__ import annotations

import numpy as np

SMOOTHING = np.array([0.25, 0.5, 0.25])


def _smooth(a: np.ndarray) -> np.ndarray:
    if len(a) < 3:
        return a
    num = np.convolve(a, SMOOTHING, mode="same")
    den = np.convolve(np.ones_like(a), SMOOTHING, mode="same")  # renormalised at both ends
    return num / den


def commands_from_poses(
    t_ns: np.ndarray, x: np.ndarray, y: np.ndarray, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Commands ``(t_ns (M,) int64, v_mps (M,), omega_rps (M,))`` from poses ``(N,)`` sorted by time.

    Poses sharing a time stamp keep only the first; fewer than two poses give no command.

    >>> t = np.array([0, 500_000_000, 1_000_000_000], dtype=np.int64)
    >>> ct, v, w = commands_from_poses(t, np.array([0.0, 0.1, 0.2]), np.zeros(3), np.zeros(3))
    >>> ct.tolist(), np.round(v, 6).tolist(), w.tolist()
    ([0, 500000000], [0.2, 0.2], [0.0, 0.0])
    """
    t = np.asarray(t_ns, dtype=np.int64)
    keep = np.concatenate([[True], np.diff(t) > 0]) if len(t) else np.zeros(0, dtype=bool)
    t, x, y, th = t[keep], np.asarray(x)[keep], np.asarray(y)[keep], np.asarray(theta)[keep]
    if len(t) < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0)
    dt = np.diff(t).astype(np.float64) / 1e9  # int64 difference first: exact for epoch stamps
    dth = np.diff(th)
    dth = np.arctan2(np.sin(dth), np.cos(dth))
    mid = th[:-1] + dth / 2
    fwd = np.diff(x) * np.cos(mid) + np.diff(y) * np.sin(mid)
    return t[:-1], _smooth(fwd / dt), _smooth(dth / dt)
