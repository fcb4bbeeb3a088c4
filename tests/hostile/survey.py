"""``python -m tests.hostile.survey [--sample]``: run the corpus outside pytest and count failures by
class and kind (traceback, exit code, leftover file, changed input, hang, …)."""

from __future__ import annotations

import sys
import tempfile
from collections import Counter
from pathlib import Path

from tests.hostile.base import build_base
from tests.hostile.cases import corpus, sample


def kind_of(message: str) -> str:
    for key, kind in (
        ("uncaught", "traceback"),
        ("a traceback", "traceback"),
        ("still running", "hang"),
        ("took", "slow"),
        ("inputs changed", "changed input"),
        ("left", "leftover file"),
        ("temp files", "leftover file"),
        ("exit -", "killed"),
        ("exit", "exit code"),
        ("not one error", "error line"),
        ("usage", "usage"),
    ):
        if key in message:
            return kind
    return "invalid output"


def main() -> None:
    cases = sample() if "--sample" in sys.argv else corpus()
    only = [a for a in sys.argv[1:] if not a.startswith("--")]
    if only:
        cases = [c for c in cases if c.cls in only]
    with tempfile.TemporaryDirectory() as tmp:
        base = build_base(Path(tmp))
        counts: Counter[tuple[str, str]] = Counter()
        total: Counter[str] = Counter()
        for i, case in enumerate(cases):
            folder = Path(tmp) / f"case{i}"
            folder.mkdir()
            total[case.cls] += 1
            try:
                from tests.hostile.runner import check

                check(case, folder, base)
            except AssertionError as exc:
                msg = str(exc)
                counts[(case.cls, kind_of(msg.splitlines()[-1]))] += 1
                print(
                    f"FAIL {kind_of(msg.splitlines()[-1]):14s} {case.cls}:{case.id}  {msg.splitlines()[-1][:150]}",
                    flush=True,
                )
                err = [ln for ln in msg.splitlines() if "Error" in ln or "error" in ln]
                if err:
                    print("     ", err[-1][:200], flush=True)
    print(f"\n{len(cases)} cases")
    for cls, n in total.items():
        kinds = {k: v for (c, k), v in counts.items() if c == cls}
        print(f"  {cls:14s} {n:4d} cases, failures: {kinds or 'none'}")


if __name__ == "__main__":
    main()
