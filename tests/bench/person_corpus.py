"""Before/after of the person model on a corpus: per-log rows of two ``lfdfuse evaluate --json``
files and the issue's four counts (run ``python tests/bench/person_corpus.py BEFORE.json AFTER.json``).

The corpus run itself is ``lfdfuse evaluate DIR… --json X.json`` on the same logs each time.
"""

from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path
from typing import Any


def _counts(logs: list[dict[str, Any]]) -> str:
    scored = [g for g in logs if "methods" in g and g["methods"]]
    m = [g["methods"] for g in scored]
    le = sum(x["fused"]["heading_error_deg"] <= x["straight"]["heading_error_deg"] for x in m)
    turns = [x for x in m if x["fused"]["turning_error_deg"] == x["fused"]["turning_error_deg"]]
    tb = sum(x["fused"]["turning_error_deg"] < x["straight"]["turning_error_deg"] for x in turns)
    disc = [x for x in m if x["fused"].get("command_accuracy") is not None]
    acc = sum(x["fused"]["command_accuracy"] >= x["straight"]["command_accuracy"] for x in disc)
    gap = statistics.median(x["fused"]["heading_error_deg"] - x["oracle"]["heading_error_deg"] for x in m)
    bc = sum(x["fused"]["heading_error_deg"] < x["bc"]["heading_error_deg"] for x in m if "bc" in x)
    mean = statistics.mean(x["fused"]["heading_error_deg"] for x in m)
    return (
        f"scored {len(scored)}/{len(logs)}; turns fused<straight {tb}/{len(turns)}; fused<=straight {le}/{len(m)};"
        f" keys fused>=straight {acc}/{len(disc)}; median fused-oracle {gap:.1f}; fused<bc {bc}/{len(m)};"
        f" mean fused {mean:.1f}"
    )


def main(paths: list[str]) -> None:
    runs = [json.loads(Path(p).read_text())["logs"] for p in paths]
    print("log".ljust(44), *(f"{Path(p).stem:>34}" for p in paths))
    print(" " * 44, *(f"{'fused oracle straight bc keys':>34}" for _ in paths))
    for rows in zip(*runs, strict=True):
        name = Path(rows[0]["path"]).name[:44]
        cells = []
        for g in rows:
            x = g.get("methods") or {}
            if not x:
                cells.append(f"{'not scored':>34}")
                continue
            k = x["fused"].get("command_accuracy")
            ks = "—" if k is None else f"{100 * k:.0f}/{100 * x['straight']['command_accuracy']:.0f}"
            cells.append(
                f"{x['fused']['heading_error_deg']:6.1f} {x['oracle']['heading_error_deg']:6.1f}"
                f" {x['straight']['heading_error_deg']:6.1f} {x['bc']['heading_error_deg']:6.1f} {ks:>7}"
            )
        print(name.ljust(44), *cells)
    for p, logs in zip(paths, runs, strict=True):
        print(f"{Path(p).stem}: {_counts(logs)}")


if __name__ == "__main__":
    main(sys.argv[1:])
