"""The parallel bench's schedule model: list scheduling of jobs that may wait for others."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from tests.bench.parallel import chain_s, list_schedule_s


def test_equal_independent_jobs_fill_the_workers_in_rounds() -> None:
    assert list_schedule_s([2.0] * 5, 2) == 6.0
    assert list_schedule_s([], 2) == 0.0


def test_a_job_that_waits_starts_when_its_job_ends_and_the_other_worker_carries_on() -> None:
    # job 1 waits for job 0; job 2 runs meanwhile on the other worker, job 3 after it
    assert list_schedule_s([3.0, 5.0, 1.0, 1.0], 2, [(), (0,), (), ()]) == 8.0
    assert chain_s([3.0, 5.0, 1.0, 1.0], [(), (0,), (), ()]) == 8.0


@settings(max_examples=50, deadline=None)
@given(st.data())
def test_the_schedule_lies_between_the_bound_and_grahams(data: st.DataObject) -> None:
    """max(total / w, costliest chain) ≤ makespan ≤ total / w + costliest chain."""
    n = data.draw(st.integers(0, 14))
    job_s = data.draw(st.lists(st.floats(0.0, 10.0), min_size=n, max_size=n))
    after = [sorted(data.draw(st.sets(st.integers(0, i - 1), max_size=2))) if i else [] for i in range(n)]
    w = data.draw(st.integers(1, 3))
    span, chain, total = list_schedule_s(job_s, w, after), chain_s(job_s, after), sum(job_s)
    assert max(total / w, chain) - 1e-9 <= span <= total / w + chain + 1e-9
