"""DDS for tests: the loopback, a domain of its own per test, and the test robot as a process.

Cyclone DDS is told to use the loopback interface with unicast discovery (no multicast here);
each test takes a DDS domain no other process on this machine holds (a lock file per domain
id: parallel pytest workers and other test runs never share one, so never hear each other).
"""

from __future__ import annotations

import fcntl
import json
import os
import random
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from tests.conftest import ROOT

LOOPBACK = (
    '<CycloneDDS><Domain><General><Interfaces><NetworkInterface name="lo"/></Interfaces>'
    '<AllowMulticast>false</AllowMulticast></General><Discovery><Peers><Peer address="127.0.0.1"/>'
    "</Peers><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex>"
    "</Discovery></Domain></CycloneDDS>"
)


_USED: set[int] = set()  # the domains this process took: never twice


@contextmanager
def own_domain() -> Iterator[int]:
    """A DDS domain id (1–232) no other process on this machine holds while the block runs."""
    folder = Path(tempfile.gettempdir()) / "lfdfuse-dds-domains"
    folder.mkdir(exist_ok=True)
    start = random.randrange(232)  # (a domain just left may still hear a participant of the last test)
    for i in range(232):
        domain = 1 + (start + i) % 232
        if domain in _USED:
            continue
        f: IO[str] = open(folder / f"{domain}.lock", "w")  # noqa: SIM115 (held while the test runs)
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            continue
        _USED.add(domain)
        try:
            yield domain
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)
            f.close()
        return
    raise RuntimeError("every DDS domain is taken")


@dataclass
class RobotProcess:
    """The test robot (:mod:`tests.support.dds_robot`) running in its own process."""

    proc: subprocess.Popen[str]
    out: Path

    def wait_ready(self, timeout_s: float = 60.0) -> None:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        assert '"ready"' in line, (line, self.proc.stderr.read() if self.proc.stderr else "")

    def result(self, timeout_s: float = 120.0) -> dict[str, Any]:
        _, err = self.proc.communicate(timeout=timeout_s)
        assert self.proc.returncode == 0, err
        data: dict[str, Any] = json.loads(self.out.read_text())
        return data

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate()


def start_robot(domain: int, out: Path, *args: str) -> RobotProcess:
    """``python -m tests.support.dds_robot --domain N --out OUT ARGS…`` (see that module)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(
        [sys.executable, "-m", "tests.support.dds_robot", "--domain", str(domain), "--out", str(out), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        cwd=ROOT,
    )
    return RobotProcess(proc, out)
