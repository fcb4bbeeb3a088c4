"""Shared CLI plumbing: consoles, error mapping, progress bars, option parsing."""

from __future__ import annotations

import functools
import math
import os
import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from lfdfuse.errors import ConfigError, LfdError

console = Console(highlight=False)
err_console = Console(stderr=True, highlight=False)
# piped output keeps its long lines whole (a file or a grep has no 80-column screen to fit)
console.soft_wrap = not console.is_terminal

F = TypeVar("F", bound=Callable[..., Any])


def user_errors(fn: F) -> F:
    """Turn an :class:`LfdError` into one ``error: …`` line on stderr and exit code 1."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            with _terminate_as_exception():
                return fn(*args, **kwargs)
        except LfdError as exc:
            err_console.print(f"error: {exc}", markup=False, soft_wrap=True)
            raise typer.Exit(1) from None
        except KeyboardInterrupt:
            # the writers' with-blocks have removed their temp files on the way out
            err_console.print("error: interrupted; nothing was written", markup=False, soft_wrap=True)
            raise typer.Exit(130) from None
        except Terminated:
            err_console.print("error: terminated; nothing was written", markup=False, soft_wrap=True)
            raise typer.Exit(143) from None

    return wrapper  # type: ignore[return-value]


class Terminated(BaseException):
    """SIGTERM, raised where the command is so that every with-block cleans up on the way out."""


def _on_sigterm(signum: int, frame: Any) -> None:
    raise Terminated


@contextmanager
def _terminate_as_exception() -> Iterator[None]:
    """While a command runs, SIGTERM unwinds it like Ctrl-C instead of killing it mid-write."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


# --- option checks: a bad value is one error line before any work is done ---------------------

#: the longest simulated run (s): a day at 10 Hz is 864,000 steps
MAX_DURATION_S = 86_400.0
#: the largest seed (numpy takes any non-negative integer; provenance keeps it as an int64)
MAX_SEED = 2**63 - 1


def check_seed(seed: int) -> int:
    if not 0 <= seed <= MAX_SEED:
        raise ConfigError(f"--seed must be an integer from 0 to 2^63-1, got {seed}")
    return seed


def check_duration(option: str, value: float, *, minimum: float = 0.1) -> float:
    """A finite duration in seconds, at least one control tick, at most a day."""
    if not math.isfinite(value) or not minimum <= value <= MAX_DURATION_S:
        raise ConfigError(
            f"{option} must be a number of seconds from {minimum:g} to {MAX_DURATION_S:g}, got {value:g}"
        )
    return value


def check_amount(option: str, value: float, *, maximum: float, unit: str) -> float:
    """A finite, non-negative amount (a noise std) no larger than ``maximum``."""
    if not math.isfinite(value) or not 0.0 <= value <= maximum:
        raise ConfigError(f"{option} must be a number from 0 to {maximum:g} {unit}, got {value:g}")
    return value


def check_count(option: str, value: int, *, maximum: int) -> int:
    if not 1 <= value <= maximum:
        raise ConfigError(f"{option} must be an integer from 1 to {maximum}, got {value}")
    return value


def _exists(p: Path) -> bool:
    try:
        return p.exists()
    except OSError:  # a name too long, a loop of links: nothing there we could overwrite
        return False


def _same(a: Path, b: Path) -> bool:
    try:
        if _exists(a) and _exists(b):
            return os.path.samefile(a, b)
    except OSError:
        pass
    return os.path.realpath(a) == os.path.realpath(b)


def existing(path: str | None) -> Path | None:
    """``path`` if it names an existing file (an input to protect), else None (a built-in name)."""
    return Path(path) if path and _exists(Path(path)) else None


def check_outputs(outputs: list[Path | None], inputs: list[Path | str | None]) -> None:
    """Refuse, before any work, outputs that would overwrite an input or each other, or that
    cannot be written (a missing folder, a folder in the way)."""
    outs = [o for o in outputs if o is not None]
    for out in outs:
        if len(out.name.encode()) > 255 - 16:  # room for the temp file's prefix and suffix
            raise ConfigError(f"cannot write {str(out)[:60]}…: the file name is too long")
    for i, out in enumerate(outs):
        for src in inputs:
            if src is not None and _same(out, Path(src)):
                raise ConfigError(f"the output {out} would overwrite the input {src}: give another path")
        for other in outs[:i]:
            if _same(out, other):
                raise ConfigError(f"two outputs are the same file {out}")
        if out.is_dir():
            raise ConfigError(f"cannot write {out}: it is a folder")
        parent = out.parent if str(out.parent) else Path(".")
        if not parent.is_dir():
            raise ConfigError(f"cannot write {out}: folder {parent} does not exist")


@contextmanager
def progress_bar(label: str) -> Iterator[Callable[[float, float], None]]:
    """A transient rich progress bar on stderr; yields an ``update(done, total)`` callback."""
    with Progress(
        TextColumn(label),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeRemainingColumn(),
        console=err_console,
        transient=True,
        disable=not err_console.is_terminal,
    ) as bar:
        task = bar.add_task(label, total=1.0)

        def update(done: float, total: float) -> None:
            bar.update(task, total=max(total, 1e-9), completed=done)

        yield update
