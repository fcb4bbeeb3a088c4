"""The report's cells: one demonstration learned, one run of a learned network, one relearning.

Each cell is a frozen record of paths and numbers and a pure function of them (``cell()``), so
:func:`~lfdfuse.evaluate.paper.suite.run_experiments` can hand them to any executor
(:mod:`lfdfuse.parallel`): in this process, or on Dask workers that read the tables and write
the logs themselves. The same seed gives the same numbers whichever executor ran them.

A learn cell names the files it writes (``table``, ``segmented``) before it runs, so the runs
and the relearning that read them can be planned with it and start as soon as it is done.
Each cell's ``cost`` is a rough estimate of its wall time, only to start the long ones first.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.evaluate.paper import experiments as ex
from lfdfuse.evaluate.paper.records import Learned, PaperRun
from lfdfuse.network.table import FusionTable, load_table
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world

T = TypeVar("T")

#: rough wall seconds per simulated second of driving a network or a teacher (and logging it)
DRIVE_S = 0.02
#: rough wall seconds per simulated second of a demo, per estimation trial (the pf estimator)
TRIAL_S = 0.004


@dataclass(frozen=True)
class LearnCell:
    """A teacher demonstrates ``legs`` in ``world``; the demo is segmented and learned."""

    key: str
    logs: Path
    world: str
    legs: tuple[Leg, ...]
    name: str
    seconds: float
    seed: int
    estimate: EstimateOptions

    @property
    def title(self) -> str:
        return f"demonstrate and learn {self.name}"

    @property
    def table(self) -> Path:
        """The learned table it writes (what the runs of it read)."""
        return self.logs / f"{self.name}.yaml"

    @property
    def segmented(self) -> Path:
        """The segmented demonstration it writes (what a relearning reads)."""
        return self.logs / f"{self.name}.seg.mcap"

    @property
    def cost(self) -> float:
        return self.seconds * (DRIVE_S + self.estimate.trials * TRIAL_S)

    def __call__(self) -> Learned:
        learned = ex.demonstrate_and_learn(
            self.logs,
            world=self.world,
            legs=self.legs,
            name=self.name,
            seconds=self.seconds,
            seed=self.seed,
            estimate=self.estimate,
        )
        # the cells that read these files were planned with the names above
        assert (learned.table_path, learned.segmented) == (self.table, self.segmented), learned
        return learned


@dataclass(frozen=True)
class RunCell:
    """A learned table (by path) driven in ``world`` from ``start`` (None: the world's)."""

    key: str
    logs: Path
    table: Path
    world: str
    start: tuple[float, float, float] | None
    seconds: float
    name: str
    label: str
    seed: int = 0

    @property
    def title(self) -> str:
        return f"run {self.name}"

    @property
    def cost(self) -> float:
        return self.seconds * DRIVE_S  # at most: a run that reaches its goal stops early

    def __call__(self) -> PaperRun:
        return ex.execute(
            self.logs,
            load_table(self.table),
            world=load_world(self.world),
            start=self.start,
            seconds=self.seconds,
            name=self.name,
            label=self.label,
            seed=self.seed,
        )


@dataclass(frozen=True)
class RelearnCell:
    """A segmented demonstration (``seconds`` long) learned again with other estimator options (the trials)."""

    key: str
    segmented: Path
    estimate: EstimateOptions
    out: Path
    seconds: float

    @property
    def title(self) -> str:
        return f"relearn {self.segmented.name} ({self.estimate.trials} trials)"

    @property
    def cost(self) -> float:
        return self.seconds * self.estimate.trials * TRIAL_S

    def __call__(self) -> FusionTable:
        return ex.relearn_table(self.segmented, estimate=self.estimate, out=self.out)


def call(cell: Callable[[], T]) -> T:
    """The job every executor runs: the cell itself."""
    return cell()


__all__ = ["LearnCell", "RelearnCell", "RunCell", "call"]
