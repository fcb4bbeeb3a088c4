"""Run one hostile case against the CLI and check the contract (DESIGN §1).

Every case: the exit code is one the case allows (1 for a user error, 2 for bad usage, 0 where
the input is still usable); a failure prints exactly one ``error: …`` line (or click's usage
error) and no traceback; a failed command leaves no new file behind, a successful one no temp
file; no input changes; the command ends in bounded time (and, for the cases that could blow
up, bounded memory).
"""

from __future__ import annotations

import hashlib
import os
import resource
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from typer.testing import CliRunner

from tests.hostile.base import Base

Content = bytes | str | Callable[[Base], bytes]


@dataclass(frozen=True)
class Case:
    """One hostile input: files to lay out, a command line, and what it may do."""

    id: str
    cls: str
    argv: tuple[str, ...]
    files: dict[str, Content] = field(default_factory=dict)
    codes: frozenset[int] = frozenset({1})
    #: run as a real process (signals, FIFOs, memory limits, real exit codes)
    process: bool = False
    mem_mb: int | None = None
    timeout_s: float = 60.0
    #: extra setup in the case folder (FIFOs, folders, permissions)
    setup: Callable[[Path], None] | None = None
    #: a signal sent this many seconds after the process started (process cases)
    signal_after: tuple[int, float] | None = None


@dataclass
class Outcome:
    code: int
    stdout: str
    stderr: str
    seconds: float
    crashed: str = ""  # an exception that escaped the CLI (in-process runs)


def _snapshot(folder: Path) -> dict[str, str]:
    out: dict[str, str] = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            p = Path(root) / name
            rel = str(p.relative_to(folder))
            if p.is_symlink() or not p.is_file():
                out[rel] = "<dir>" if p.is_dir() else "<special>"
            else:
                try:
                    out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
                except OSError:
                    out[rel] = "<unreadable>"
    return out


def lay_out(case: Case, folder: Path, base: Base) -> None:
    for name, content in case.files.items():
        p = folder / name
        p.parent.mkdir(parents=True, exist_ok=True)
        data = content(base) if callable(content) else content
        p.write_bytes(data.encode() if isinstance(data, str) else data)
    if case.setup is not None:
        case.setup(folder)


def _limit(mem_mb: int | None) -> Callable[[], None]:
    def pre() -> None:
        os.setsid()
        # as from a shell: a test run earlier in this worker may have left SIGINT ignored (or
        # blocked), and both are inherited (Python then never raises KeyboardInterrupt in the command)
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
        if mem_mb is not None:
            resource.setrlimit(resource.RLIMIT_AS, (mem_mb * 2**20, mem_mb * 2**20))

    return pre


def run_process(case: Case, folder: Path) -> Outcome:
    env = dict(os.environ, COLUMNS="100", PYTHONFAULTHANDLER="1")
    t0 = time.monotonic()
    proc = subprocess.Popen(
        [sys.executable, "-m", "lfdfuse", *case.argv],
        cwd=folder,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=_limit(case.mem_mb),
        env=env,
    )
    if case.signal_after is not None:
        # mid-write: once the command's temp output exists, wait ``after`` more, then signal
        sig, after = case.signal_after
        deadline = time.monotonic() + case.timeout_s / 2
        while proc.poll() is None and time.monotonic() < deadline:
            if any(p.name.endswith(".tmp") for p in folder.iterdir()):
                break
            time.sleep(0.02)
        try:
            proc.wait(timeout=after)
        except subprocess.TimeoutExpired:
            proc.send_signal(sig)
    try:
        out, err = proc.communicate(timeout=case.timeout_s)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        return Outcome(-999, out.decode(errors="replace"), err.decode(errors="replace"), case.timeout_s)
    return Outcome(
        proc.returncode, out.decode(errors="replace"), err.decode(errors="replace"), time.monotonic() - t0
    )


def run_inprocess(case: Case, folder: Path) -> Outcome:
    from lfdfuse.cli.main import app

    old = os.getcwd()
    os.chdir(folder)
    t0 = time.monotonic()
    try:
        res = CliRunner().invoke(app, list(case.argv))
    finally:
        os.chdir(old)
    crashed = ""
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        crashed = f"{res.exception.__class__.__name__}: {res.exception}"
    return Outcome(res.exit_code, res.stdout, res.stderr, time.monotonic() - t0, crashed)


def check(case: Case, folder: Path, base: Base) -> Outcome:
    """Run ``case`` in the empty ``folder``; assert the contract; return what happened."""
    lay_out(case, folder, base)
    before = _snapshot(folder)
    outcome = run_process(case, folder) if case.process else run_inprocess(case, folder)
    after = _snapshot(folder)
    # a read-only folder of a case must become writable again before anything else
    for root, dirs, _files in os.walk(folder):
        for d in dirs:
            os.chmod(Path(root) / d, 0o755)
    where = f"[{case.cls}] {case.id}: lfdfuse {' '.join(case.argv)}\n--- stderr\n{outcome.stderr[-2000:]}"
    assert not outcome.crashed, f"{where}\nuncaught {outcome.crashed}"
    assert "Traceback" not in outcome.stderr + outcome.stdout, f"{where}\na traceback"
    assert outcome.code != -999, f"{where}\nstill running after {case.timeout_s} s"
    assert outcome.seconds <= case.timeout_s, f"{where}\ntook {outcome.seconds:.1f} s"
    assert outcome.code in case.codes, f"{where}\nexit {outcome.code}, expected one of {sorted(case.codes)}"
    changed = [k for k, v in before.items() if after.get(k) != v]
    assert not changed, f"{where}\ninputs changed or removed: {changed}"
    new = sorted(set(after) - set(before))
    if outcome.code != 0:
        assert not new, f"{where}\na failed command left {new}"
    assert not [n for n in new if n.endswith(".tmp")], f"{where}\ntemp files left: {new}"
    lines = [ln for ln in outcome.stderr.splitlines() if ln.strip()]
    if outcome.code == 1 or outcome.code >= 128 or outcome.code < 0:
        assert len(lines) == 1 and lines[0].startswith("error: "), f"{where}\nnot one error: line"
    if outcome.code == 2:
        assert "Usage" in outcome.stderr + outcome.stdout, f"{where}\nno usage message"
    if outcome.code == 0:
        _check_outputs(folder, new, where)
    return outcome


def _check_outputs(folder: Path, new: list[str], where: str) -> None:
    """What a successful command wrote must itself be valid."""
    import json

    from lfdfuse.errors import LfdError
    from lfdfuse.log.reader import file_info
    from lfdfuse.network.table import load_table

    for name in new:
        p = folder / name
        try:
            if name.endswith(".yaml"):
                load_table(p)
            elif name.endswith(".mcap"):
                file_info(p)
            elif name.endswith(".json"):
                json.loads(p.read_text())
        except (LfdError, ValueError) as exc:
            raise AssertionError(f"{where}\nexit 0 wrote an invalid {name}: {exc}") from exc
