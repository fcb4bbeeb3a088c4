"""Jobs, their outcomes and the progress of a batch: what every executor shares.

A job is a pure function of one picklable item (paths and numbers, never arrays: workers read
their own inputs). An executor runs a batch of them and yields each :class:`Outcome` as it
finishes, in any order; :class:`Batch` turns that stream into :class:`Event` s for a progress
bar and collects the outcomes **by job index**, so the result never depends on which worker
finished first.

A job may wait for others (``after``: it reads what they wrote, a learned table say), and may
say what it costs: :class:`Batch` hands the jobs to the executor critical path first
(:func:`critical_path_order`), so a long chain starts at once instead of after the short jobs,
and a job starts as soon as the jobs it waits for have finished (no barrier between stages).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import Any, Generic, Protocol, TypeVar

from lfdfuse.errors import LfdError

T = TypeVar("T")
R = TypeVar("R")
S = TypeVar("S")


@dataclass(frozen=True)
class Outcome(Generic[R]):
    """What one job gave: its ``value``, or the one-line ``error`` it failed with."""

    index: int
    value: R | None
    error: str | None
    seconds: float  # wall time inside the job (for cost models; never part of a result)

    @property
    def ok(self) -> bool:
        return self.error is None


def guarded(fn: Callable[[T], R], index: int, item: T) -> Outcome[R]:
    """Run one job; a user error (:class:`LfdError`) becomes the outcome's one-line ``error``.

    Anything else is a bug and propagates (with its traceback) to whoever collects the batch.
    """
    began = time.perf_counter()
    try:
        value = fn(item)
    except LfdError as exc:
        line = " ".join(str(exc).split()) or type(exc).__name__
        return Outcome(index, None, line, time.perf_counter() - began)
    return Outcome(index, value, None, time.perf_counter() - began)


def guarded_after(fn: Callable[[T], R], index: int, item: T, *needs: Outcome[Any]) -> Outcome[R]:
    """:func:`guarded`, once the jobs it waits for finished (their ``needs`` outcomes); if one of
    them failed, this job fails too without running."""
    if not all(o.ok for o in needs):
        return Outcome(index, None, "not run: a job it waits for failed", 0.0)
    return guarded(fn, index, item)


def check_after(after: Sequence[Sequence[int]] | None, jobs: int) -> tuple[tuple[int, ...], ...]:
    """``after`` as tuples, one per job (none: no job waits); a job waits only for earlier jobs."""
    if after is None:
        return ((),) * jobs
    if len(after) != jobs:
        raise ValueError("one 'after' entry per job")
    out = tuple(tuple(a) for a in after)
    for i, needs in enumerate(out):
        if any(not 0 <= j < i for j in needs):
            raise ValueError(f"job {i} may wait only for earlier jobs, not {needs}")
    return out


def critical_path_order(costs: Sequence[float], after: Sequence[Sequence[int]] | None = None) -> list[int]:
    """The jobs in the order to start them: the longest chain to the end first.

    A job's rank is its cost plus the most expensive chain of jobs waiting on it (its "bottom
    level", the list-scheduling heuristic), ties by index. A job ranks at least as high as the
    later jobs that wait for it (costs ≥ 0), so the order keeps every job after the ones it waits
    for; with no ``after`` it is longest-first; with equal costs and no ``after``, the jobs' own order.
    """
    needs = check_after(after, len(costs))
    if any(c < 0 for c in costs):
        raise ValueError("a job's cost is at least 0")
    rank = [float(c) for c in costs]
    for i in reversed(range(len(costs))):  # the jobs waiting on i come after i
        for j in needs[i]:
            rank[j] = max(rank[j], costs[j] + rank[i])
    return sorted(range(len(costs)), key=lambda i: (-rank[i], i))


class Executor(Protocol):
    """Runs jobs; ``slots`` is how many run at once."""

    @property
    def slots(self) -> int: ...

    def run(
        self, fn: Callable[[T], R], items: Sequence[T], *, after: Sequence[Sequence[int]] | None = None
    ) -> Iterator[Outcome[R]]:
        """Every item's outcome, in the order the jobs finish; the items start in their order as
        far as the jobs they wait for let them (``after[i]``: earlier items, see :func:`guarded_after`)."""
        ...


class InProcess:
    """The default executor: the jobs one after another in this process (no Dask imported)."""

    @property
    def slots(self) -> int:
        return 1

    def run(
        self, fn: Callable[[T], R], items: Sequence[T], *, after: Sequence[Sequence[int]] | None = None
    ) -> Iterator[Outcome[R]]:
        needs = check_after(after, len(items))
        outs: list[Outcome[R]] = []
        for i, item in enumerate(items):
            outs.append(guarded_after(fn, i, item, *(outs[j] for j in needs[i])))
            yield outs[-1]


@dataclass(frozen=True)
class Event:
    """Progress of a batch: counts so far, and the job that just finished (``index`` −1 at the start)."""

    total: int
    done: int  # finished without error
    failed: int
    running: int  # started and not finished (at most the executor's slots)
    index: int = -1
    label: str = ""
    error: str | None = None

    @property
    def finished(self) -> int:
        return self.done + self.failed


class Batch(Generic[T, R, S]):
    """A batch of jobs on an executor: iterate for :class:`Event` s, then ask for the ``result``.

    ``reduce`` turns the outcomes, in job order, into the batch's result (a summary, a table).
    ``after[i]``: the earlier jobs job ``i`` waits for; ``costs``: what each job costs (any unit,
    an estimate): the executor gets the jobs in :func:`critical_path_order` (as given without
    costs). Iterating twice does not rerun anything; ``result()`` runs what is left without events.
    """

    def __init__(
        self,
        fn: Callable[[T], R],
        items: Sequence[T],
        *,
        executor: Executor,
        reduce: Callable[[tuple[Outcome[R], ...]], S],
        labels: Sequence[str] | None = None,
        after: Sequence[Sequence[int]] | None = None,
        costs: Sequence[float] | None = None,
    ) -> None:
        if labels is not None and len(labels) != len(items):
            raise ValueError("one label per job")
        if costs is not None and len(costs) != len(items):
            raise ValueError("one cost per job")
        needs = check_after(after, len(items))
        #: the order the executor gets the jobs in (its item k is job ``order[k]``)
        self.order = tuple(critical_path_order(costs if costs is not None else [0.0] * len(items), needs))
        at = {job: k for k, job in enumerate(self.order)}
        self._after = tuple(tuple(sorted(at[j] for j in needs[job])) for job in self.order)
        self._fn, self._items, self._executor, self._reduce = fn, tuple(items), executor, reduce
        self.labels = (
            tuple(labels) if labels is not None else tuple(f"job {i + 1}" for i in range(len(items)))
        )
        self._outcomes: dict[int, Outcome[R]] = {}
        self._events: Iterator[Event] | None = None

    def __len__(self) -> int:
        return len(self._items)

    def __iter__(self) -> Iterator[Event]:
        if self._events is None:
            self._events = self._stream()
        return self._events

    def _stream(self) -> Iterator[Event]:
        total = len(self._items)
        slots = max(1, self._executor.slots)
        done = failed = 0
        yield Event(total, 0, 0, min(slots, total))
        items = [self._items[job] for job in self.order]
        for out in self._executor.run(self._fn, items, after=self._after):
            out = replace(out, index=self.order[out.index])
            self._outcomes[out.index] = out
            done += out.ok
            failed += not out.ok
            left = total - done - failed
            yield Event(total, done, failed, min(slots, left), out.index, self.labels[out.index], out.error)

    @property
    def outcomes(self) -> tuple[Outcome[R], ...]:
        """Every outcome in job order (runs whatever has not run yet)."""
        for _ in self:
            pass
        return tuple(self._outcomes[i] for i in range(len(self._items)))

    @property
    def failures(self) -> tuple[tuple[str, str], ...]:
        """``(label, error)`` of every failed job, in job order."""
        return tuple((self.labels[o.index], o.error) for o in self.outcomes if o.error is not None)

    def result(self) -> S:
        return self._reduce(self.outcomes)
