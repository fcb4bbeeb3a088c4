"""A generated off-route world as a world file: ``python -m lfdfuse.tools.generated_world SEED``.

Prints the world of :mod:`lfdfuse.world.generate` for ``SEED`` (tuning seeds 0–999, held-apart
seeds 1000–1999) as YAML, to look at or to hand to ``lfdfuse simulate --world``.
"""

from __future__ import annotations

import sys

from lfdfuse.world.generate import generate_offroute


def main(argv: list[str]) -> int:
    if len(argv) != 1 or not argv[0].isdigit():
        print("usage: python -m lfdfuse.tools.generated_world SEED", file=sys.stderr)
        return 1
    print(generate_offroute(int(argv[0])).source, end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
