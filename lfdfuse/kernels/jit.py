"""Compiled kernels: numba where it imports and compiles, the numpy reference everywhere else.

A hot loop is written twice: the numpy reference (vectorised, what the tests trust) and a plain
loop for numba. :func:`kernel` wraps the loop; nothing is imported or compiled until the first
:meth:`Kernel.ready`, so ``lfdfuse --help`` and ``inspect`` never pay for numba. Compiled code is
cached on disk (numba's ``cache=True``: beside the module, or in the user's cache folder when
that is not writable), so only the first run after an install compiles.

A compiled loop cannot call a plain Python function: a helper it calls is named in ``calls``
(``kernel(loop, calls=[helper])``), compiled with it, and the loop sees the compiled helper under
the helper's own name (the module keeps the plain function); a helper may call the helpers named
before it.

``LFDFUSE_KERNELS=numpy`` runs every reference instead (the tests compare the two; the
benchmarks time both in one run). When numba is missing or a kernel fails to compile, the
reference runs and one warning says so.

>>> import os
>>> double = kernel(lambda x: 2.0 * x)
>>> os.environ[MODE] = "numpy"
>>> double.ready()
False
>>> del os.environ[MODE]
"""

from __future__ import annotations

import os
import signal
import threading
import types
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

#: environment variable choosing the kernels: ``numba`` (the default) or ``numpy``
MODE = "LFDFUSE_KERNELS"

_numba: dict[str, Any] = {}


#: the environment as ``os.environ`` keeps it (its raw values by encoded name), and the name of
#: :data:`MODE` there: one dict lookup per :func:`compiled_wanted` instead of ``os.environ.get``'s
#: encode, look-up and decode (a kernel is asked whether it is ready several times a tick)
_ENVIRON: dict[Any, Any] | None = getattr(os.environ, "_data", None)
_KEY: Any = os.environ.encodekey(MODE) if hasattr(os.environ, "encodekey") else None
#: the raw value of :data:`MODE` last read, and what it said
_seen: list[Any] = [object(), True]


def compiled_wanted() -> bool:
    """True unless ``LFDFUSE_KERNELS=numpy`` asks for the numpy references (read afresh at every
    call: a change of ``os.environ`` takes effect at once)."""
    if _ENVIRON is None or _KEY is None:
        return os.environ.get(MODE, "numba").strip().lower() != "numpy"
    raw = _ENVIRON.get(_KEY)
    if raw is not _seen[0]:
        _seen[0], _seen[1] = raw, os.environ.get(MODE, "numba").strip().lower() != "numpy"
    return bool(_seen[1])


def _first_line(exc: BaseException) -> str:
    """An exception's message as one line (numba's typing errors run to dozens of lines)."""
    lines = str(exc).strip().splitlines()
    return lines[0].strip() if lines else type(exc).__name__


@contextmanager
def _signals_held() -> Iterator[None]:
    """Ctrl-C and SIGTERM wait while numba imports, compiles or loads its cache, then act.

    LLVM calls back into Python there (its object cache), and an exception raised inside such a
    callback is swallowed ("Exception ignored"): the interrupt would be lost, or the process
    would die by the signal after the command had handled it. Held here, the signal reaches the
    handler it was meant for once the kernel is ready (a few seconds at most, once per install).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held: list[int] = []

    def hold(signum: int, frame: Any) -> None:
        held.append(signum)

    previous: dict[int, Any] = {}
    for wanted in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(wanted) is not None:  # installed from outside Python: left alone
            previous[wanted] = signal.signal(wanted, hold)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if held:
            first = held[0]
            handler = previous[first]
            if callable(handler):
                handler(first, None)  # raises KeyboardInterrupt, or the command's own exception
            elif handler == signal.SIG_DFL:
                signal.raise_signal(first)


def _import_numba() -> Any:
    """The numba module, imported once; None (with one warning) when it cannot be."""
    if "module" not in _numba:
        try:
            import numba
        except Exception as exc:  # an ImportError, or llvmlite failing to load on this platform
            _numba["module"] = None
            warnings.warn(
                f"compiled kernels unavailable ({_first_line(exc)}); running the numpy references",
                RuntimeWarning,
                2,
            )
        else:
            _numba["module"] = numba
    return _numba["module"]


class Warmup:
    """Calls a process answers with the numpy references before it loads compiled loops: loading
    numba and its cached kernels costs about a second of CPU, more than a short run's calls take
    in numpy (the answers are the same either way). One per family of loops; call it once a call."""

    def __init__(self, calls: int) -> None:
        self.left = calls

    @property
    def done(self) -> bool:
        """Whether the family has made its warm-up calls (without counting one)."""
        return self.left <= 0

    def __call__(self) -> bool:
        """True once the family has made its warm-up calls (this one counts)."""
        if self.left > 0:
            self.left -= 1
            return False
        return True


class Kernel:
    """A loop compiled by numba on first use, or None of it when it cannot be (see :meth:`ready`)."""

    def __init__(
        self,
        fn: Callable[..., Any],
        *,
        signature: str | None = None,
        calls: Sequence[Callable[..., Any]] = (),
        specialise_on: int | None = None,
    ) -> None:
        self.fn = fn
        self.signature = signature
        self.calls = tuple(calls)
        self.specialise_on = specialise_on
        self._compiled: Callable[..., Any] | None = None
        self._failed = False
        self._warm = False  # called once: compiled for its argument types, or loaded from the cache
        self._warm_lengths: set[int] = set()  # with ``specialise_on``: the lengths compiled or loaded

    def ready(self) -> bool:
        """True when the compiled loop can run: compiled kernels are wanted, numba imports and
        this loop compiles (eagerly when it has a signature). False means: run the reference."""
        if not compiled_wanted() or self._failed:
            return False
        if self._compiled is not None:
            return True
        with _signals_held():
            return self._compile()

    def warm_for(self, length: int | None = None) -> bool:
        """Whether the loop (with ``specialise_on``: for that length) is compiled or loaded
        already: a call of it then costs no compilation, and may run off the main thread."""
        if self._compiled is None:
            return False
        return self._warm if self.specialise_on is None else length in self._warm_lengths

    def _compile(self) -> bool:
        numba = _import_numba()
        if numba is None:
            self._failed = True
            return False
        try:
            opts: dict[str, Any] = {"cache": True, "nogil": True, "fastmath": False, "error_model": "numpy"}
            fn = _with_compiled(self.fn, self.calls, numba.njit(**opts))
            # with a signature numba compiles now (a typing error shows here); without, at the first call
            self._compiled = (
                numba.njit(self.signature, **opts)(fn) if self.signature else numba.njit(**opts)(fn)
            )
        except Exception as exc:  # a typing error on this platform's numba: the reference still runs
            self._failed = True
            name = getattr(self.fn, "__name__", "kernel")
            warnings.warn(
                f"kernel {name} did not compile ({_first_line(exc)}); running its numpy reference",
                RuntimeWarning,
                2,
            )
            return False
        return True

    def __call__(self, *args: Any) -> Any:
        if self._compiled is None and not self.ready():
            raise RuntimeError("compiled kernel called without ready(): call its numpy reference instead")
        assert self._compiled is not None
        if self.specialise_on is not None:  # one compiled loop per length of that tuple argument
            length = len(args[self.specialise_on])
            if length in self._warm_lengths:
                return self._compiled(*args)
            with _signals_held():
                result = self._compiled(*args)
            self._warm_lengths.add(length)
            return result
        if self._warm:
            return self._compiled(*args)
        with _signals_held():  # without a signature, numba compiles (or loads) on the first call
            result = self._compiled(*args)
        self._warm = True
        return result


def _with_compiled(
    fn: Callable[..., Any], calls: tuple[Callable[..., Any], ...], jit: Any
) -> Callable[..., Any]:
    """``fn`` reading each helper of ``calls`` (by its name) as compiled by ``jit``: the same code
    over a copy of its module's globals, so the module's own name still holds the plain helper."""
    if not calls:
        return fn
    code = getattr(fn, "__code__", None)
    if code is None:
        raise TypeError(f"{fn!r} is not a plain function: it cannot call compiled helpers")
    names: dict[str, Any] = {}
    for h in calls:  # in order: a helper may call the helpers named before it
        names[h.__name__] = jit(_rebound(h, names))
    used = set(code.co_names).union(*(h.__code__.co_names for h in calls))
    missing = sorted(set(names) - used)
    if missing:
        raise TypeError(f"{fn.__name__} calls no {', '.join(missing)}")
    return _rebound(fn, names)


def _rebound(fn: Callable[..., Any], names: dict[str, Any]) -> Callable[..., Any]:
    """``fn`` over a copy of its module's globals in which ``names`` stand (the same code)."""
    code = fn.__code__
    if not any(n in code.co_names for n in names):
        return fn
    copy = types.FunctionType(code, {**fn.__globals__, **names}, fn.__name__, fn.__defaults__, fn.__closure__)
    copy.__qualname__ = fn.__qualname__
    copy.__module__ = fn.__module__
    copy.__doc__ = fn.__doc__
    return copy


def kernel(
    fn: Callable[..., Any] | None = None,
    *,
    signature: str | None = None,
    calls: Sequence[Callable[..., Any]] = (),
    specialise_on: int | None = None,
) -> Any:
    """Decorate a numba-compatible loop as a lazily compiled :class:`Kernel` (``calls``: the
    plain helpers it calls, compiled with it; ``specialise_on``: the index of a tuple argument
    whose length the loop is compiled for, once per length, each held from signals while it
    compiles or loads)."""
    if fn is None:
        return lambda f: Kernel(f, signature=signature, calls=calls, specialise_on=specialise_on)
    return Kernel(fn, signature=signature, calls=calls, specialise_on=specialise_on)
