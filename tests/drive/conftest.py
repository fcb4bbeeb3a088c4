"""Shared rigs of the drive tests: a keep-left table learned in ``building``, and a live run."""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from lfdfuse.drive.options import DriveOptions, DriveSummary, Stopper
from lfdfuse.drive.session import drive
from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.network.table import FusionTable, write_table
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from tests.conftest import ROOT


@pytest.fixture(scope="session")
def keep_left(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped keep-left demo in ``building``, segmented and estimated: a fusion table file.

    Estimated by NNLS (``estimate --method nnls``, 0.6 s against the sampler's 10–17 s here): the
    default sampler's closed-loop quality is tested in ``tests/execute``; these tests need a
    learned table, and it drives ``tee`` the same (about 24 m in 60 s, on the left, no collision).
    """
    tmp = tmp_path_factory.mktemp("keep-left")
    seg = tmp / "kl.seg.mcap"
    segment_file(ROOT / "sample_logs" / "keep-left-building.mcap", out=seg, measure_lag=False)
    table, _, _ = estimate_run(read_segmented(seg), opts=EstimateOptions(seed=1, method="nnls"), name="kl")
    path = tmp / "keep-left.yaml"
    write_table(table, path)
    return path


@dataclass
class Live:
    """A drive session running in a thread, its notes, and how it ended."""

    stopper: Stopper = field(default_factory=Stopper)
    notes: list[str] = field(default_factory=list)
    summary: DriveSummary | None = None
    error: BaseException | None = None
    thread: threading.Thread | None = None

    def join(self, timeout: float = 60.0) -> DriveSummary:
        assert self.thread is not None
        self.thread.join(timeout)
        assert not self.thread.is_alive(), "drive did not stop"
        if self.error is not None:
            raise self.error
        assert self.summary is not None
        return self.summary


def start_drive(table: FusionTable, url: str, *, out: Path | None = None, **kw: object) -> Live:
    """``drive`` against ``url`` in a background thread (stop it with ``live.stopper.stop``)."""
    live = Live()
    opts = DriveOptions(table=table, url=url, **kw)  # type: ignore[arg-type]

    def target() -> None:
        try:
            live.summary = drive(opts, out=out, notify=live.notes.append, stopper=live.stopper)
        except BaseException as exc:  # handed to the test thread by join()
            live.error = exc

    live.thread = threading.Thread(target=target, daemon=True)
    live.thread.start()
    return live


def in_thread(fn: Callable[[], object]) -> threading.Thread:
    th = threading.Thread(target=fn, daemon=True)
    th.start()
    return th
