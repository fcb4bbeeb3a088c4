"""Jobs, their outcomes and the progress of a batch: what every executor shares.

A job is a pure function of one picklable item (paths and numbers, never arrays: workers read
their own inputs). An executor runs a batch of them and yields each :class:`Outcome` as it
finishes, in any order; :class:`Batch` turns that stream into :class:`Event` s for a progress
bar and collects the outcomes **by job index**, so the result never depends on which worker
finished first.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Generic, Protocol, TypeVar

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


class Executor(Protocol):
    """Runs independent jobs; ``slots`` is how many run at once."""

    @property
    def slots(self) -> int: ...

    def run(self, fn: Callable[[T], R], items: Sequence[T]) -> Iterator[Outcome[R]]:
        """Every item's outcome, in the order the jobs finish."""
        ...


class InProcess:
    """The default executor: the jobs one after another in this process (no Dask imported)."""

    @property
    def slots(self) -> int:
        return 1

    def run(self, fn: Callable[[T], R], items: Sequence[T]) -> Iterator[Outcome[R]]:
        for i, item in enumerate(items):
            yield guarded(fn, i, item)


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
    Iterating twice does not rerun anything; ``result()`` runs what is left without events.
    """

    def __init__(
        self,
        fn: Callable[[T], R],
        items: Sequence[T],
        *,
        executor: Executor,
        reduce: Callable[[tuple[Outcome[R], ...]], S],
        labels: Sequence[str] | None = None,
    ) -> None:
        if labels is not None and len(labels) != len(items):
            raise ValueError("one label per job")
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
        for out in self._executor.run(self._fn, self._items):
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
