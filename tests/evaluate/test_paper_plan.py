"""The report's plan (:func:`lfdfuse.evaluate.paper.suite.plan_cells`): what each cell waits for
and the order the executor gets them in — planned, not run (no timing)."""

from __future__ import annotations

from pathlib import Path

import pytest

from lfdfuse.evaluate.paper.cells import LearnCell, RelearnCell, RunCell
from lfdfuse.evaluate.paper.suite import PaperOptions, plan_cells
from lfdfuse.parallel.jobs import critical_path_order
from tests.bench.parallel import list_schedule_s


def _makespan(costs: tuple[float, ...], after: tuple[tuple[int, ...], ...], order: list[int]) -> float:
    """The jobs list-scheduled on 2 workers, handed out in ``order`` (as :class:`Batch` does)."""
    at = {job: k for k, job in enumerate(order)}
    return list_schedule_s([costs[j] for j in order], 2, [sorted(at[j] for j in after[i]) for i in order])


@pytest.mark.parametrize("quick", [False, True])
def test_each_cell_waits_only_for_the_learn_that_writes_what_it_reads(quick: bool) -> None:
    plan = plan_cells(PaperOptions(logs=Path("/nowhere"), quick=quick))
    learns = {i: c for i, c in enumerate(plan.cells) if isinstance(c, LearnCell)}
    for cell, after in zip(plan.cells, plan.after, strict=True):
        if isinstance(cell, LearnCell):
            assert after == ()
        elif isinstance(cell, RunCell):
            assert [learns[j].table for j in after] == [cell.table]
        else:  # the trials' relearning: after the three-goal demo, not after every learn (no barrier)
            assert isinstance(cell, RelearnCell)
            assert [learns[j].segmented for j in after] == [cell.segmented]
            assert learns[after[0]].key == "task"


def test_the_three_goal_demo_and_its_relearning_start_first_then_longest_first() -> None:
    plan = plan_cells(PaperOptions(logs=Path("/nowhere")))
    order = critical_path_order(plan.costs, plan.after)
    first, second = (plan.cells[i] for i in order[:2])
    assert isinstance(first, LearnCell) and first.key == "task"
    assert isinstance(second, RelearnCell) and second.estimate.trials == 30
    rest = order[2:]
    kinds = [type(plan.cells[i]) for i in rest]
    assert kinds == sorted(kinds, key=lambda k: k is RunCell)  # the other learns, then the runs
    runs = [plan.costs[i] for i in rest if isinstance(plan.cells[i], RunCell)]
    assert runs == sorted(runs, reverse=True)


def test_on_two_workers_the_estimated_grid_takes_well_under_its_serial_time() -> None:
    """The plan's own cost estimates, list-scheduled on 2 workers: the relearning runs beside the
    rest (within 10 % of half the total); in two waves (every run and the relearning, last,
    after every learn) it did not."""
    plan = plan_cells(PaperOptions(logs=Path("/nowhere")))
    total = sum(plan.costs)
    span = _makespan(plan.costs, plan.after, critical_path_order(plan.costs, plan.after))
    assert span <= 1.1 * total / 2
    learns = tuple(i for i, c in enumerate(plan.cells) if isinstance(c, LearnCell))
    waves = tuple(() if i in learns else learns for i in range(len(plan.cells)))
    assert _makespan(plan.costs, waves, list(range(len(plan.cells)))) > 1.2 * total / 2
