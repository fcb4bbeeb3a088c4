"""What a re-estimated table changed, step by step, in words (``teleop --table`` after a correction).

:func:`step_changes` compares two tables of one task goal step by goal step (top-level steps
by name): a step whose sub-goals differ is written out as its new landmark steps, a step with
the same leaves as the rows it re-weights or adds; either says in how many of its steps the
weights for unseen BACs changed. Steps that did not change say nothing.
"""

from __future__ import annotations

from lfdfuse.network.table import FusionTable, Step, named_leaf_steps


def _leaves(step: Step) -> list[tuple[str, Step]]:
    if step.network is None:
        return [(step.name, step)]
    return named_leaf_steps(FusionTable((), {}, step.network))


def _rows(old: Step, new: Step) -> tuple[int, int]:
    """Rows of ``new`` whose weights differ from ``old``'s, and rows ``old`` did not have."""
    before = {r.bac: r.weights for r in old.fusion}
    changed = sum(1 for r in new.fusion if r.bac in before and r.weights != before[r.bac])
    return changed, sum(1 for r in new.fusion if r.bac not in before)


def _landmarks(leaves: list[tuple[str, Step]]) -> str:
    return " → ".join(
        f"{name} ({s.landmark.describe()})" if s.landmark is not None else name for name, s in leaves
    )


def step_changes(old: FusionTable, new: FusionTable) -> list[str]:
    """One line per goal step ``new`` adds, re-structures or re-weights compared with ``old``."""
    before = {s.name: s for s in old.network.steps}
    lines: list[str] = []
    for step in new.network.steps:
        was = before.get(step.name)
        if was is None:
            lines.append(f"{step.name}: a new step")
            continue
        a, b = _leaves(was), _leaves(step)
        changed = new_rows = 0
        old_by = dict(a)
        safer = sum(1 for n, y in b if n in old_by and y.default_weights != old_by[n].default_weights)
        unseen = f"; its weights for unseen BACs changed in {safer} step(s)" if safer else ""
        if [n for n, _ in a] == [n for n, _ in b] and all(
            x.landmark == y.landmark for (_, x), (_, y) in zip(a, b, strict=False)
        ):
            for (_, x), (_, y) in zip(a, b, strict=True):
                c, n = _rows(x, y)
                changed, new_rows = changed + c, new_rows + n
            if changed or new_rows or safer:
                lines.append(f"{step.name}: re-weights {changed} row(s), adds {new_rows} row(s){unseen}")
            continue
        for name, y in b:
            if name in old_by:
                c, n = _rows(old_by[name], y)
                changed, new_rows = changed + c, new_rows + n
        rows = f"; {changed} row(s) re-weighted, {new_rows} added" if changed or new_rows else ""
        lines.append(f"{step.name}: now {_landmarks(b)}{rows}{unseen}")
    return lines
