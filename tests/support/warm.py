"""``python -m tests.support.warm``: compile (or load) the numba kernels once, before the tests start.

On a fresh clone numba's on-disk cache is empty, and every test process that reaches a kernel
before another has written it compiles the same loop again: the two pytest workers and the
commands the tests start, side by side. This runs a short pipeline in one process, in a
temporary folder: a continuous demo learned and driven, a keyboard demo learned by its key
presses, a goal task learned and driven, and the full catalogue learned. Each kernel these reach
is compiled once and written to the cache. Where the package's cache folders hold compiled
kernels already, nothing runs (a test that needs a kernel not yet cached compiles it, as before).
Exit 1, with the command's output, when a step fails.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from typer.testing import CliRunner

from lfdfuse.cli.main import app

ROOT = Path(__file__).resolve().parents[2]
TASK = ROOT / "sample_logs" / "three-goals.task.yaml"


def steps(d: Path) -> list[list[str]]:
    """The commands, in order; each reads only what an earlier one wrote into ``d``."""
    return [
        ["simulate", "--duration", "30", "--seed", "1", "-o", f"{d}/c.mcap"],
        ["segment", f"{d}/c.mcap"],
        ["estimate", f"{d}/c.seg.mcap", "-o", f"{d}/c.yaml"],
        ["segment", f"{d}/c.mcap", "--behaviors", "full", "-o", f"{d}/f.seg.mcap"],
        ["estimate", f"{d}/f.seg.mcap", "-o", f"{d}/f.yaml"],
        ["execute", f"{d}/c.yaml", "--max-time", "5", "-o", f"{d}/c-run.mcap"],
        ["simulate", "--teacher", "keep-left", "--keys", "0.8", "--duration", "30", "--seed", "1"]
        + ["-o", f"{d}/k.mcap"],
        ["segment", f"{d}/k.mcap"],
        ["estimate", f"{d}/k.seg.mcap", "-o", f"{d}/k.yaml"],
        ["simulate", "--teacher", str(TASK), "--duration", "120", "--seed", "1", "-o", f"{d}/t.mcap"],
        ["segment", f"{d}/t.mcap"],
        ["estimate", f"{d}/t.seg.mcap", "-o", f"{d}/t.yaml"],
        ["execute", f"{d}/t.yaml", "--max-time", "5", "-o", f"{d}/t-run.mcap"],
    ]


def cached() -> bool:
    """Whether numba's cache beside the package's modules holds any compiled kernel."""
    return any((ROOT / "lfdfuse").rglob("__pycache__/*.nbi"))


def main() -> int:
    if cached():
        return 0
    runner = CliRunner()
    with tempfile.TemporaryDirectory(prefix="lfdfuse-warm-") as tmp:
        for args in steps(Path(tmp)):
            res = runner.invoke(app, args)
            if res.exit_code != 0:
                print(f"warm-up: lfdfuse {' '.join(args)} failed:\n{res.output}", file=sys.stderr)
                return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
