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
from lfdfuse.parallel import Batch, InProcess, Outcome, check_executor, guarded, open_executor
from tests.conftest import ROOT

T = TypeVar("T")
R = TypeVar("R")


def _square_or_fail(x: int) -> int:
    if x % 5 == 3:
        raise ConfigError(f"job {x} is bad\non two lines")
    return x * x


class Shuffled:
    """An executor that completes its jobs in a random order, two 'slots' wide."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    @property
    def slots(self) -> int:
        return 2

    def run(self, fn: Callable[[T], R], items: Sequence[T]) -> Iterator[Outcome[R]]:
        for i in self.rng.permutation(len(items)):
            yield guarded(fn, int(i), items[int(i)])


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
