"""The executor seam: independent jobs in this process (the default) or on Dask when asked.

    with open_executor(workers=2) as ex:           # a LocalCluster of 2 processes
        batch = Batch(job, items, executor=ex, reduce=summarise)
        for event in batch: ...                     # progress (done / running / failed)
        result = batch.result()                     # outcomes in job order, reduced

``open_executor()`` with neither option runs in-process and imports no Dask.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterator
from contextlib import contextmanager

from lfdfuse.errors import ConfigError
from lfdfuse.parallel.jobs import Batch, Event, Executor, InProcess, Outcome, guarded

#: the most local workers one command starts (a LocalCluster beyond that is a mistake, not a plan)
MAX_WORKERS = 256

_ADDRESS = re.compile(r"^(tcp|tls|inproc|ucx|ws|wss)://[^\s/]+$")


def check_executor(*, workers: int | None, scheduler: str | None) -> None:
    """A one-line :class:`ConfigError` for options that cannot name an executor."""
    if workers is not None and scheduler is not None:
        raise ConfigError("give --workers or --scheduler, not both")
    if workers is not None and not 1 <= workers <= MAX_WORKERS:
        raise ConfigError(f"--workers must be an integer from 1 to {MAX_WORKERS}, got {workers}")
    if scheduler is not None and not _ADDRESS.match(scheduler):
        raise ConfigError(f"--scheduler must be an address like tcp://HOST:8786, got {scheduler!r}")


@contextmanager
def open_executor(*, workers: int | None = None, scheduler: str | None = None) -> Iterator[Executor]:
    """In-process by default; ``workers``: a Dask ``LocalCluster``; ``scheduler``: an existing cluster."""
    check_executor(workers=workers, scheduler=scheduler)
    if workers is None and scheduler is None:
        yield InProcess()
        return
    try:
        # imported here, not above: the in-process default must not load Dask (an optional
        # dependency boundary, not a cycle: cluster imports only jobs)
        from lfdfuse.parallel import cluster
    except ImportError as exc:
        raise ConfigError(
            f"--workers/--scheduler need Dask: pip install 'dask[distributed]' ({exc})"
        ) from None
    ex = cluster.local_cluster(workers) if workers is not None else cluster.connect(str(scheduler))
    try:
        yield ex
    finally:
        # a closing cluster logs its workers' shutdown; none of that is the user's business
        quiet = logging.getLogger("distributed")
        level = quiet.level
        quiet.setLevel(logging.CRITICAL)
        try:
            ex.close()
        finally:
            quiet.setLevel(level)


__all__ = [
    "MAX_WORKERS",
    "Batch",
    "Event",
    "Executor",
    "InProcess",
    "Outcome",
    "check_executor",
    "guarded",
    "open_executor",
]
