"""Shared CLI plumbing: consoles, error mapping, progress bars, option parsing."""

from __future__ import annotations

import functools
import math
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from lfdfuse.errors import ConfigError, LfdError


class PipedConsole(Console):
    """rich's console, but a closed pipe is left to :func:`user_errors` (rich exits 1 on it)."""

    def on_broken_pipe(self) -> None:
        raise BrokenPipeError


console = PipedConsole(highlight=False)
err_console = PipedConsole(stderr=True, highlight=False)
# piped output keeps its long lines whole (a file or a grep has no 80-column screen to fit)
console.soft_wrap = not console.is_terminal

F = TypeVar("F", bound=Callable[..., Any])


def user_errors(fn: F) -> F:
    """Turn an :class:`LfdError` into one ``error: …`` line on stderr and exit code 1."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            with _terminate_as_exception():
                result = fn(*args, **kwargs)
                sys.stdout.flush()  # a closed pipe shows here, not at exit after click's handler
                return result
        except BrokenPipeError:
            # `lfdfuse … | head`: the reader has what it wanted; the rest goes nowhere, success
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            raise typer.Exit(0) from None
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


# --- option ranges: typer checks them before any work is done; out of range is a usage error
# (exit 2, click's message); what only the library can judge (a start pose in a wall, a lag
# longer than the log) stays the library's, as one ``error:`` line and exit 1

#: the longest simulated run (s): a day at 10 Hz is 864,000 steps
MAX_DURATION_S = 86_400.0
#: the largest seed (numpy takes any non-negative integer; provenance keeps it as an int64)
MAX_SEED = 2**63 - 1
#: the largest sensor noise std (m): beyond a metre a scan says nothing
MAX_SENSOR_NOISE_M = 1.0


def finite(value: float | None) -> float | None:
    """A typer callback refusing NaN and ±inf (click's ranges let NaN through)."""
    if value is not None and not math.isfinite(value):
        raise typer.BadParameter(f"{value} is not a finite number")
    return value


def positive(value: float | None) -> float | None:
    """A typer callback for a limit: finite and above zero (a limit of 0 or less would be dropped)."""
    if value is not None and not (math.isfinite(value) and value > 0):
        raise typer.BadParameter(f"{value} is not a positive number")
    return value


def checked(parse: Callable[[str], object]) -> Callable[[str | None], str | None]:
    """A typer callback that runs ``parse`` on the option's text as it is read, so a value outside
    what the option accepts is a usage error (exit 2) before anything runs, not a failure later."""

    def check(text: str | None) -> str | None:
        if text is not None:
            try:
                parse(text)
            except (ConfigError, ValueError) as exc:
                raise typer.BadParameter(str(exc)) from None
        return text

    return check


def start_option() -> Any:
    """``--start X,Y,THETA``: the start pose, checked as it is read."""
    from lfdfuse.robot.pose import Pose

    return typer.Option(
        None,
        "--start",
        callback=checked(Pose.parse),
        help="Start pose X,Y,THETA (m, m, rad); default: the world's.",
    )


def seed_option(help: str, default: int = 0) -> Any:
    """``--seed``: an integer from 0 to 2^63-1."""
    return typer.Option(default, "--seed", min=0, max=MAX_SEED, help=help)


def duration_option(default: float | None, *names: str, help: str) -> Any:
    """A duration in seconds: finite, at least one control tick, at most a day."""
    return typer.Option(default, *names, min=0.1, max=MAX_DURATION_S, callback=finite, help=help)


def sensor_noise_option() -> Any:
    """``--sensor-noise``: the std (m) of Gaussian range noise, 0 to 1 m."""
    return typer.Option(
        0.0,
        "--sensor-noise",
        min=0.0,
        max=MAX_SENSOR_NOISE_M,
        callback=finite,
        help="Std (m) of Gaussian range noise on laser and sonar.",
    )


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
