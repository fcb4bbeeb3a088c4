"""Goals off the style's route: the full table of :mod:`tests.support.offroute`.

Two buildings, the teacher's start and 10 perturbed starts (3 with ``--quick``), with and
without sub-goals, and the ring-spur task run in a larger building of the same topology. One row
per (world, method, start): completed in order, collisions, time.

    python -m tests.bench.run --suite offroute
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any

from lfdfuse.world.model import load_world
from tests.support.offroute import CASES, demonstrate, learn_case, perturbed_starts, run_starts


def run(quick: bool = False) -> list[dict[str, Any]]:
    n = 3 if quick else 10
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for case in CASES.values():
            seg = demonstrate(case, folder=folder)
            world = case.load()
            starts = perturbed_starts(world, n, seed=15)
            for sub in (False, True):
                table = learn_case(seg, subgoals=sub)
                label = f"{world.name}/{'subgoals' if sub else 'reactive'}"
                rows += run_starts(table, case, starts=starts, folder=folder, label=label)
                if world.name in TRANSFER:
                    # learned in one building, run in another of the same topology and other sizes
                    other, max_time_s = TRANSFER[world.name]
                    far = perturbed_starts(load_world(other), n, seed=15)
                    longer = replace(case, max_time_s=max_time_s)
                    rows += run_starts(
                        table, longer, world=other, starts=far, folder=folder, label=f"{label}->{other}"
                    )
    return rows


#: transfer runs: learned in the key's world, run in (world, time limit) — a larger building needs longer
TRANSFER = {"ring-spur": ("ring-spur-large", 600.0)}


if __name__ == "__main__":
    for row in run(quick="--quick" in sys.argv):
        print(row)
