"""Compiled kernels: a signal that arrives while numba compiles acts once the kernel is ready."""

from __future__ import annotations

import os
import signal
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lfdfuse.kernels import jit


def _sum(x: np.ndarray) -> float:
    total = 0.0
    for v in x:
        total += v
    return total


def test_an_interrupt_during_compilation_is_raised_after_it() -> None:
    """Ctrl-C while a kernel compiles: the kernel finishes, then KeyboardInterrupt reaches the caller."""
    before = signal.signal(
        signal.SIGINT, signal.default_int_handler
    )  # as in a command (a test worker may ignore it)
    try:
        _interrupted_while_compiling()
    finally:
        signal.signal(signal.SIGINT, before)


def _interrupted_while_compiling() -> None:
    k = jit.Kernel(_sum)
    inside: list[bool] = []
    with pytest.raises(KeyboardInterrupt):
        with jit._signals_held():
            os.kill(os.getpid(), signal.SIGINT)
            inside.append(True)  # not interrupted here
            if k.ready():
                assert k(np.arange(4.0)) == 6.0
            inside.append(True)
    assert inside == [True, True]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_held_sigterm_reaches_the_commands_own_handler() -> None:
    seen: list[int] = []

    def handler(signum: int, frame: Any) -> None:
        seen.append(signum)

    before = signal.signal(signal.SIGTERM, handler)
    try:
        with jit._signals_held():
            os.kill(os.getpid(), signal.SIGTERM)
            assert seen == []
        assert seen == [signal.SIGTERM]
        assert signal.getsignal(signal.SIGTERM) is handler
    finally:
        signal.signal(signal.SIGTERM, before)


def test_nothing_held_runs_as_before() -> None:
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    with jit._signals_held():
        pass
    assert {s: signal.getsignal(s) for s in before} == before


def test_the_kernel_mode_follows_the_environment_at_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """``compiled_wanted`` reads its answer afresh: set, changed and unset between two calls."""
    monkeypatch.delenv(jit.MODE, raising=False)
    assert jit.compiled_wanted()
    for value, wanted in (("numpy", False), (" NumPy ", False), ("numba", True), ("numpy", False)):
        monkeypatch.setenv(jit.MODE, value)
        assert jit.compiled_wanted() is wanted
        assert jit.compiled_wanted() is wanted
    monkeypatch.delenv(jit.MODE)
    assert jit.compiled_wanted()


@given(st.integers(min_value=0, max_value=50))
def test_a_warmup_answers_in_numpy_for_its_calls_then_compiled(calls: int) -> None:
    warm = jit.Warmup(calls)
    seen = [(warm.done, warm()) for _ in range(calls + 3)]
    assert [w for _, w in seen] == [False] * calls + [True] * 3
    assert [d for d, _ in seen] == [calls == 0] + [i >= calls for i in range(1, calls + 3)]
