"""The executor seam: outcomes by job index whatever the completion order, failures that stay one
line and let the rest carry on, progress that adds up, and no Dask on the default path."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable, Iterator, Sequence
from typing import TypeVar

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.errors import ConfigError, LfdError
from lfdfuse.parallel import Batch, InProcess, Outcome, check_executor, open_executor
from lfdfuse.parallel.jobs import check_after, critical_path_order, guarded_after
from tests.conftest import ROOT

T = TypeVar("T")
R = TypeVar("R")


def _square_or_fail(x: int) -> int:
    if x % 5 == 3:
        raise ConfigError(f"job {x} is bad\non two lines")
    return x * x


class Shuffled:
    """An executor that completes its jobs in a random order (a job only after those it waits
    for), two 'slots' wide; ``given``: the items in the order it got them."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)
        self.given: list[object] = []

    @property
    def slots(self) -> int:
        return 2

    def run(
        self, fn: Callable[[T], R], items: Sequence[T], *, after: Sequence[Sequence[int]] | None = None
    ) -> Iterator[Outcome[R]]:
        needs = check_after(after, len(items))
        self.given = list(items)
        outs: dict[int, Outcome[R]] = {}
        while len(outs) < len(items):
            ready = [i for i in range(len(items)) if i not in outs and all(j in outs for j in needs[i])]
            i = int(self.rng.choice(ready))
            outs[i] = guarded_after(fn, i, items[i], *(outs[j] for j in needs[i]))
            yield outs[i]


def _collect(outs: tuple[Outcome[int], ...]) -> list[int | str | None]:
    return [o.value if o.ok else o.error for o in outs]


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 40), st.integers(0, 2**32))
def test_results_do_not_depend_on_completion_order(n: int, seed: int) -> None:
    items = list(range(n))
    serial = Batch(_square_or_fail, items, executor=InProcess(), reduce=_collect)
    shuffled = Batch(_square_or_fail, items, executor=Shuffled(seed), reduce=_collect)
    assert serial.result() == shuffled.result()
    assert [o.index for o in shuffled.outcomes] == items


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 40), st.integers(0, 2**32))
def test_progress_adds_up_and_failures_carry_their_own_line(n: int, seed: int) -> None:
    batch = Batch(_square_or_fail, list(range(n)), executor=Shuffled(seed), reduce=_collect)
    events = list(batch)
    assert len(events) == n + 1 and events[0].finished == 0
    for a, b in zip(events, events[1:], strict=False):
        assert b.finished == a.finished + 1
        assert 0 <= b.running <= min(2, n - b.finished)
    bad = [x for x in range(n) if x % 5 == 3]
    assert events[-1].failed == len(bad) and events[-1].done == n - len(bad)
    assert batch.failures == tuple((f"job {x + 1}", f"job {x} is bad on two lines") for x in bad)
    for ev in events[1:]:
        assert (ev.error is None) == (ev.index % 5 != 3)
    assert list(batch) == []  # iterating again reruns nothing


@st.composite
def _jobs(draw: st.DrawFn) -> tuple[list[float], list[tuple[int, ...]]]:
    """Costs (≥ 0, ties likely) and, per job, some earlier jobs it waits for."""
    n = draw(st.integers(0, 16))
    costs = [float(c) for c in draw(st.lists(st.integers(0, 5), min_size=n, max_size=n))]
    after = [tuple(sorted(draw(st.sets(st.integers(0, i - 1), max_size=2)))) if i else () for i in range(n)]
    return costs, after


def _chain_costs(costs: Sequence[float], after: Sequence[Sequence[int]]) -> list[float]:
    """Each job's cost plus the most expensive chain of jobs waiting on it (every chain walked)."""

    def chain(i: int) -> float:
        waiting = [k for k in range(len(costs)) if i in after[k]]
        return costs[i] + max((chain(k) for k in waiting), default=0.0)

    return [chain(i) for i in range(len(costs))]


@settings(max_examples=60, deadline=None)
@given(_jobs())
def test_the_order_starts_the_longest_chain_first_and_keeps_what_waits_after(
    jobs: tuple[list[float], list[tuple[int, ...]]],
) -> None:
    costs, after = jobs
    order = critical_path_order(costs, after)
    assert sorted(order) == list(range(len(costs)))
    at = {job: k for k, job in enumerate(order)}
    assert all(at[j] < at[i] for i in range(len(costs)) for j in after[i])
    chains = _chain_costs(costs, after)
    ranks = [chains[i] for i in order]
    assert ranks == sorted(ranks, reverse=True)
    # independent jobs: longest first, ties (and equal costs) in their own order
    assert critical_path_order(costs) == sorted(range(len(costs)), key=lambda i: (-costs[i], i))
    assert critical_path_order([0.0] * len(costs), after) == list(range(len(costs)))  # free: as given


@settings(max_examples=25, deadline=None)
@given(_jobs(), st.integers(0, 2**32))
def test_jobs_that_wait_give_the_same_results_in_any_order_and_a_failure_stops_what_waits(
    jobs: tuple[list[float], list[tuple[int, ...]]], seed: int
) -> None:
    costs, after = jobs
    items = list(range(len(costs)))
    serial = Batch(_square_or_fail, items, executor=InProcess(), reduce=_collect, after=after)
    shuffled_ex = Shuffled(seed)
    shuffled = Batch(_square_or_fail, items, executor=shuffled_ex, reduce=_collect, after=after, costs=costs)
    assert serial.result() == shuffled.result()
    assert shuffled_ex.given == [items[i] for i in critical_path_order(costs, after)]
    failed: set[int] = set()
    for i in items:  # a job fails on its own (x % 5 == 3) or when one it waits for failed
        if i % 5 == 3 or any(j in failed for j in after[i]):
            failed.add(i)
    for i, got in enumerate(serial.result()):
        if i in failed and i % 5 != 3:
            assert got == "not run: a job it waits for failed"
        else:
            assert (i in failed) == isinstance(got, str)


def test_a_job_waits_only_for_earlier_jobs() -> None:
    with pytest.raises(ValueError, match="earlier"):
        Batch(_square_or_fail, [1, 2], executor=InProcess(), reduce=_collect, after=[(1,), ()])
    with pytest.raises(ValueError, match="at least 0"):
        critical_path_order([1.0, -1.0])


def test_a_bug_is_not_swallowed() -> None:
    def broken(x: int) -> int:
        raise ZeroDivisionError("a bug")

    with pytest.raises(ZeroDivisionError):
        Batch(broken, [1], executor=InProcess(), reduce=_collect).result()


@pytest.mark.parametrize(
    ("workers", "scheduler", "match"),
    [(2, "tcp://h:8786", "not both"), (0, None, "--workers"), (None, "h:8786", "--scheduler")],
)
def test_bad_executor_options_are_one_error(workers: int | None, scheduler: str | None, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        check_executor(workers=workers, scheduler=scheduler)


def test_an_unreachable_scheduler_is_one_error() -> None:
    from lfdfuse.parallel.cluster import connect

    with pytest.raises(LfdError, match="cannot reach the Dask scheduler"):
        connect("tcp://127.0.0.1:9", timeout_s=1.0)


def test_the_in_process_default_imports_no_dask(tmp_path: object) -> None:
    """The CLI and an in-process batch (real jobs: two short execute runs) load no Dask."""
    code = f"""
import sys
from typer.testing import CliRunner
from lfdfuse.cli.main import app
table = {str(ROOT / "lfdfuse" / "evaluate" / "truths" / "corridor-center.yaml")!r}
res = CliRunner().invoke(app, ["execute", table, "--world", "corridor", "--starts", "2", "--max-time", "1"])
assert res.exit_code == 0, res.output
with __import__("lfdfuse.parallel", fromlist=["open_executor"]).open_executor() as ex:
    assert type(ex).__name__ == "InProcess"
loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("dask", "distributed"))
assert not loaded, loaded
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr


def test_open_executor_defaults_to_in_process() -> None:
    with open_executor() as ex:
        assert isinstance(ex, InProcess) and ex.slots == 1
