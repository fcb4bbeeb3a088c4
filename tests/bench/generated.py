"""Sub-goals that carry: the three-goal task in generated off-route worlds held apart.

The first 20 worlds of :data:`~tests.support.generated_worlds.BENCH_SEEDS` (4 with ``--quick``) — a
corridor ring, green at the end of a dead-end spur off it, side openings on the way, never tuned
on nor looked at — each demonstrated once by the scripted teacher and learned without and with
sub-goals (:mod:`tests.support.generated`); each table runs from 3 perturbed starts (±0.5 m,
±20°) and may take 1.5 times the teacher's time. One row per world (runs completed in order
without collision, out of 3, per variant; the sub-goal landmarks; the step each failed run with
sub-goals ended in), then one row per variant over the set with its Wilson 95 % interval and the
worlds whose every run completed (the starts of one world mostly end alike).

The README gives the rate on fresh seeds (80 worlds, 240 runs) and how much blocks of worlds
differ; this suite is the quick, repeatable check of the same thing on its 20 worlds.

    python -m tests.bench.run --suite generated
"""

from __future__ import annotations

import sys
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

from tests.support.generated import GeneratedOutcome, completion, run_generated
from tests.support.generated_worlds import BENCH_SEEDS, offroute_spec

VARIANTS = ("reactive", "subgoals")


def world_row(o: GeneratedOutcome) -> dict[str, Any]:
    spec = offroute_spec(o.seed)
    row: dict[str, Any] = {
        "name": spec.name,
        "spur": f"{spec.spur.leg} {spec.spur.side} {spec.spur.length_m:g} m",
        "openings": len(spec.decoys),
        "width_m": spec.width_m,
        "teacher_s": round(o.demo_s, 1),
    }
    for v in VARIANTS:
        done = o.completed(v)
        row[v] = f"{sum(done)}/{len(done)}" if o.demo_completed else "teacher failed"
    row["landmarks"] = "; ".join(o.landmarks.get("subgoals", ()))
    ended = Counter(str(r["ended_in"]) for r in o.rows if r["name"] == "subgoals" and not r["completed"])
    row["subgoals_failed_in"] = "; ".join(f"{step or 'the end'} ×{n}" for step, n in sorted(ended.items()))
    return row


def summary_rows(outcomes: list[GeneratedOutcome], label: str) -> list[dict[str, Any]]:
    rows = []
    for v in VARIANTS:
        c = completion(outcomes, v)
        lo, hi = c.ci95
        rows.append(
            {
                "name": f"{label}/{v}",
                "completed": c.completed,
                "runs": c.runs,
                "worlds": c.worlds,
                "rate": c.rate,
                "ci95": [round(lo, 3), round(hi, 3)],
                # the starts of one world mostly end alike (after red the runs converge): the
                # worlds whose every run completed say as much as the runs
                "worlds_all_completed": sum(1 for o in outcomes if o.demo_completed and all(o.completed(v))),
            }
        )
    return rows


def run(
    quick: bool = False, *, seeds: range = BENCH_SEEDS, label: str = "held-apart"
) -> list[dict[str, Any]]:
    chosen = seeds[: 4 if quick else 20]
    with tempfile.TemporaryDirectory() as tmp:
        outcomes = [run_generated(s, folder=Path(tmp) / str(s), starts=3) for s in chosen]
    return [world_row(o) for o in outcomes] + summary_rows(outcomes, label)


if __name__ == "__main__":
    from tests.support.generated_worlds import TUNING_SEEDS

    tuning = "--tuning" in sys.argv
    for row in run(
        quick="--quick" in sys.argv,
        seeds=TUNING_SEEDS if tuning else BENCH_SEEDS,
        label="tuning" if tuning else "held-apart",
    ):
        print(row)
