"""Teach again on generated worlds held apart: one correction where a sub-goal table fails.

From seed 1640 up (never used before: the ``generated`` bench and the README's rate stop at
1639), every generated off-route world's three-goal demo is learned with sub-goals and run from 4
perturbed starts; where one fails, one scripted correction from the first failing start (the
teacher's path where the robot left it or before it hit a wall, :mod:`tests.support.corrections`)
and a re-estimate of demo and correction with sub-goals (:mod:`tests.support.taught_again`). Worlds are taken until
``WANTED`` have a failing start (8 with ``--quick``), at most ``MAX_WORLDS``. One row per world
with a failing start, then the summary: fixed (the failing start and ≥ 2 of 3 others complete)
and regressions (starts that completed before and fail after).

    python -m tests.bench.run --suite corrections

Run alone it takes seed ranges, keeps every world's folder (``--keep DIR``: a world screened
there before is not screened again, so learning corrections anew costs only the correction and
the runs after), writes a JSON line per world as it finishes (``--json FILE``), and can screen
only (``--screen-only``)::

    python -m tests.bench.corrections --seeds 1648-1699,1704-1759 --keep /tmp/corr --json corr.jsonl
"""

from __future__ import annotations

import argparse
import json
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from tests.support.corrections import TAKEOVERS
from tests.support.taught_again import TaughtAgain, screen, summary, teach_again, teach_again_screened

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


def seeds_of(text: str) -> list[int]:
    """``1648-1699,1704`` → the seeds, in order."""
    out: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out += range(int(lo), int(hi or lo) + 1)
    return out


def run_seeds(
    seeds: Iterable[int],
    *,
    keep: Path,
    out: Path | None,
    screen_only: bool = False,
    takeovers: int = TAKEOVERS,
) -> dict[str, Any]:
    worlds: list[TaughtAgain] = []
    for seed in seeds:
        folder = keep / str(seed)
        folder.mkdir(parents=True, exist_ok=True)
        s = screen(seed, folder=folder)
        if screen_only:
            row: dict[str, Any] = {
                "name": f"offroute-{seed}",
                "teacher": "completed" if s.demo_completed else "failed",
                "before": "".join("✓" if ok else "✗" for ok in s.before),
                "wall_s": {k: round(v, 1) for k, v in s.times.items()},
            }
        else:
            w = teach_again_screened(s, folder=folder, takeovers=takeovers)
            worlds.append(w)
            row = w.row()
        if out is not None:
            with out.open("a") as f:
                f.write(json.dumps(row, ensure_ascii=False) + "\n")
        print(row, flush=True)
    return {"name": "summary", **summary(worlds)}


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--seeds", help="seed ranges, e.g. 1648-1699,1704")
    ap.add_argument("--keep", type=Path, help="keep every world's folder here (and reuse its screening)")
    ap.add_argument("--json", type=Path, help="append a JSON line per world")
    ap.add_argument("--screen-only", action="store_true")
    ap.add_argument(
        "--takeovers",
        type=int,
        default=TAKEOVERS,
        help="a person who watches on takes over up to this many times in the one correction (1: once)",
    )
    a = ap.parse_args()
    if a.seeds is None:
        for r in run(quick=a.quick):
            print(r, flush=True)
    else:
        keep = a.keep or Path(tempfile.mkdtemp(prefix="corrections-"))
        print(
            run_seeds(
                seeds_of(a.seeds), keep=keep, out=a.json, screen_only=a.screen_only, takeovers=a.takeovers
            ),
            flush=True,
        )
