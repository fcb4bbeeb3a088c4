"""Peak memory of ``segment`` and ``estimate`` on a long demo (at most 300 MB for an hour's demo).

Each stage runs in its own process (``/usr/bin/time``-like: ``ru_maxrss`` of the child), so the
numbers are what a user sees: the interpreter, numpy and the stage's own arrays. The demo is a
keep-left tour of the default world, simulated once per run of the benchmark.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

#: the goal for an hour-long demo, per stage (MB)
GOAL_MB = 300.0


def run(quick: bool = False) -> list[dict[str, Any]]:
    """Rows ``{name, log_min, peak_mb, seconds, goal_mb}`` per stage, for a 60-minute demo (6 in quick)."""
    minutes = 6.0 if quick else 60.0
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        demo, seg, table = Path(tmp) / "demo.mcap", Path(tmp) / "demo.seg.mcap", Path(tmp) / "fusion.yaml"
        stages = [
            ("simulate", ["simulate", "--duration", str(60 * minutes), "-o", str(demo)]),
            ("segment", ["segment", str(demo), "-o", str(seg)]),
            ("estimate", ["estimate", str(seg), "-o", str(table)]),
        ]
        for name, argv in stages:
            # a fresh interpreter per stage, so a stage's peak is its own
            code = (
                "import resource, subprocess, sys; "
                f"r = subprocess.run([sys.executable, '-m', 'lfdfuse', *{argv!r}], capture_output=True); "
                "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, r.returncode)"
            )
            t0 = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
            kb, rc = (int(v) for v in out.stdout.split())
            if rc != 0:
                raise RuntimeError(f"lfdfuse {name} failed (exit {rc})")
            rows.append(
                {
                    "name": name,
                    "log_min": minutes,
                    "peak_mb": round(kb / 1024.0, 1),
                    "seconds": round(time.perf_counter() - t0, 1),
                    "goal_mb": GOAL_MB if name != "simulate" else None,
                }
            )
    return rows


if __name__ == "__main__":
    for row in run(quick="--quick" in sys.argv):
        print(row)
