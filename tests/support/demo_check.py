"""``python -m tests.support.demo_check``: did ``make demo`` learn? Exit 1 when learning clearly failed.

Compares each learned run's report with what its teacher showed: the keep-left run must keep
its left wall nearer than its right (the teacher's style) without collisions; the task run must
complete the task it was taught.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any


def problems(left: dict[str, Any], task: dict[str, Any]) -> list[str]:
    """What went clearly wrong in the two demo runs (empty: learning worked)."""
    out: list[str] = []
    if not left["left_range_mean_m"] < left["right_range_mean_m"]:
        out.append(
            f"the keep-left network does not keep left (left {left['left_range_mean_m']:.2f} m,"
            f" right {left['right_range_mean_m']:.2f} m)"
        )
    if left["collisions"] > 0:
        out.append(f"the keep-left network collided {left['collisions']} times")
    if task["completed"] is not True:
        reached = sum(g["reached"] for g in task["goals"])
        out.append(f"the three-goal network reached {reached} of {len(task['goals'])} goals")
    return out


def main(folder: str) -> int:
    left = json.loads((Path(folder) / "left-run.json").read_text())
    task = json.loads((Path(folder) / "task-run.json").read_text())
    found = problems(left, task)
    for p in found:
        print(f"demo: LEARNING FAILED: {p}", file=sys.stderr)
    if not found:
        print("demo: the learned networks drive like their teachers (keeps left; task completed)")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/demo"))
