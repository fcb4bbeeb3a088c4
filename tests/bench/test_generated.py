"""The generated-worlds bench's rows: per world the runs completed and where the failed ones ended;
per variant the runs and the worlds completed from every start."""

from __future__ import annotations

from typing import Any

from tests.bench.generated import summary_rows, world_row
from tests.support.generated import GeneratedOutcome


def _outcome(
    seed: int, sub: list[tuple[bool, str]], reactive: list[bool], demo: bool = True
) -> GeneratedOutcome:
    rows: list[dict[str, Any]] = [
        {"name": "subgoals", "completed": ok, "ended_in": "" if ok else step} for ok, step in sub
    ]
    rows += [
        {"name": "reactive", "completed": ok, "ended_in": "" if ok else "reach-green"} for ok in reactive
    ]
    return GeneratedOutcome(
        seed, demo, 200.0, 300.0, {"subgoals": ("turn-left: turned 70° to the left",)}, tuple(rows)
    )


def test_a_world_row_counts_the_runs_and_says_where_the_failed_ones_ended() -> None:
    o = _outcome(
        1040,
        [(True, ""), (False, "reach-blue/reach-blue"), (False, "reach-blue/reach-blue")],
        [False, False, True],
    )
    row = world_row(o)
    assert row["name"] == "offroute-1040"
    assert row["subgoals"] == "1/3" and row["reactive"] == "1/3"
    assert row["subgoals_failed_in"] == "reach-blue/reach-blue ×2"
    assert row["landmarks"] == "turn-left: turned 70° to the left"


def test_the_summary_counts_runs_and_the_worlds_completed_from_every_start() -> None:
    done = [(True, "")] * 3
    outcomes = [
        _outcome(1040, done, [True, True, True]),
        _outcome(1041, [(True, ""), (True, ""), (False, "reach-green/to-left-opening-2")], [False] * 3),
        _outcome(1042, done, [False] * 3, demo=False),  # the teacher failed: no runs counted
    ]
    rows = {r["name"]: r for r in summary_rows(outcomes, "held-apart")}
    sub, react = rows["held-apart/subgoals"], rows["held-apart/reactive"]
    assert (sub["completed"], sub["runs"], sub["worlds"], sub["worlds_all_completed"]) == (5, 6, 2, 1)
    assert (react["completed"], react["runs"], react["worlds_all_completed"]) == (3, 6, 1)
    lo, hi = sub["ci95"]
    assert lo < 5 / 6 < hi
