"""Teach again on generated worlds held apart: one correction where a sub-goal table fails.

From seed 1640 up (never used before: the ``generated`` bench and the README's rate stop at
1639), every generated off-route world's three-goal demo is learned with sub-goals and run from 4
perturbed starts; where one fails, one scripted correction from the first failing start (the
teacher's path where the robot left it, :mod:`tests.support.corrections`) and a re-estimate of
demo and correction with sub-goals (:mod:`tests.support.taught_again`). Worlds are taken until
``WANTED`` have a failing start (8 with ``--quick``), at most ``MAX_WORLDS``. One row per world
with a failing start, then the summary: fixed (the failing start and ≥ 2 of 3 others complete)
and regressions (starts that completed before and fail after).

    python -m tests.bench.run --suite corrections
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path
from typing import Any

from tests.support.taught_again import TaughtAgain, summary, teach_again

FIRST_SEED = 1640
WANTED = 20
MAX_WORLDS = 240


def run(quick: bool = False, *, first: int = FIRST_SEED, wanted: int | None = None) -> list[dict[str, Any]]:
    want = wanted if wanted is not None else (8 if quick else WANTED)
    worlds: list[TaughtAgain] = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(first, first + MAX_WORLDS):
            worlds.append(teach_again(seed, folder=Path(tmp) / str(seed)))
            if sum(w.failing is not None for w in worlds) >= want:
                break
    return [w.row() for w in worlds if w.failing is not None] + [{"name": "summary", **summary(worlds)}]


if __name__ == "__main__":
    for row in run(quick="--quick" in sys.argv):
        print(row, flush=True)
