"""Behaviour cloning: the baseline a user would pick instead of fusion (``bc`` in ``evaluate``).

From the same training steps the fusion is fitted on, a k-nearest-neighbours regression maps
what the scanner sees — the nearest return in each of ``sectors`` equal sectors round the robot,
clipped at ``clip_m`` (:func:`sector_features`) — to the demonstrated heading, regressed as
``(cos, sin)`` so that headings either side of ±π average to a heading, not to its opposite.
No primitive enters: where ``bc`` beats ``fused`` the data holds more than these primitives
express; where neither beats ``straight``, the data is too little or too noisy for either.

k-nearest neighbours has no randomness (ties between equally near neighbours go to the earlier
training step, scikit-learn's brute-force search being stable), so the same training steps give
the same predictions on every machine.
"""

from __future__ import annotations

import math

import numpy as np

from lfdfuse.behaviors.primitives import distinct_beams
from lfdfuse.robot.readings import ScanGeometry

#: sectors round the robot (30° each) and the range they are clipped at (m)
SECTORS = 12
CLIP_M = 4.0
#: neighbours averaged (fewer when training has fewer steps)
NEIGHBOURS = 5


def sector_features(
    ranges_m: np.ndarray, geometry: ScanGeometry, *, sectors: int = SECTORS, clip_m: float = CLIP_M
) -> np.ndarray:
    """``(N, sectors)``: per scan of ``ranges_m (N, B)`` the nearest return (m) in each sector.

    Sector ``j`` spans bearings ``[−π + j·w, −π + (j+1)·w)`` (``w = 2π / sectors``) in the robot's
    frame. A beam counts as a return as the primitives count one (finite, above 0, below the
    scanner's max range); a sector without a return, or outside the scanner's field of view,
    reads ``clip_m``, as does anything farther.
    """
    r = np.asarray(ranges_m, dtype=np.float64)
    n = r.shape[0]
    out = np.full((n, sectors), clip_m)
    if n == 0 or geometry.count == 0:
        return out
    ang = np.arctan2(np.sin(geometry.angles), np.cos(geometry.angles))
    which = np.clip(((ang + math.pi) / (2 * math.pi) * sectors).astype(np.int64), 0, sectors - 1)
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(r) & (r > 0.0) & (r < geometry.max_range_m) & distinct_beams(geometry)[None, :]
    near = np.where(valid, np.minimum(r, clip_m), clip_m)
    for j in range(sectors):
        cols = which == j
        if cols.any():
            out[:, j] = near[:, cols].min(axis=1)
    return out


def clone_headings(
    train_x: np.ndarray, train_heading: np.ndarray, test_x: np.ndarray, *, neighbours: int = NEIGHBOURS
) -> np.ndarray:
    """Predicted headings (rad) ``(M,)`` of ``test_x (M, F)`` by the mean direction of the
    ``neighbours`` nearest training rows ``train_x (T, F)`` (headings ``train_heading (T,)``, rad),
    nearer ones weighing more. No training row: straight ahead (0)."""
    if len(test_x) == 0:
        return np.zeros(0)
    if len(train_x) == 0:
        return np.zeros(len(test_x))
    # imported here: scikit-learn takes a second to import, and only evaluate needs it
    from sklearn.neighbors import KNeighborsRegressor

    knn = KNeighborsRegressor(
        n_neighbors=min(neighbours, len(train_x)), weights="distance", algorithm="brute"
    )
    knn.fit(train_x, np.column_stack([np.cos(train_heading), np.sin(train_heading)]))
    unit = np.asarray(knn.predict(test_x))
    moving = np.hypot(unit[:, 0], unit[:, 1]) > 1e-9
    return np.asarray(np.where(moving, np.arctan2(unit[:, 1], unit[:, 0]), 0.0))
