"""The report's experiments in order: styles, junctions, the three-goal task, trials, obstacles.

:func:`run_experiments` is an iterator of :class:`ExperimentEvent` (the CLI turns them into a
progress bar); its last event carries the :class:`~lfdfuse.evaluate.paper.records.PaperResults`.
The logs and tables behind every number are written to the options' ``logs`` folder.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lfdfuse.errors import LfdError
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.evaluate.paper import experiments as ex
from lfdfuse.evaluate.paper.compare import style_errors
from lfdfuse.evaluate.paper.records import STYLES, Learned, PaperResults, Run, junction_choice
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world


@dataclass(frozen=True)
class PaperOptions:
    """``quick``: shorter demonstrations and runs, fewer starts and trials (a smoke test, ~30 s)."""

    logs: Path
    seed: int = 1
    quick: bool = False

    @property
    def trials(self) -> int:
        return 2 if self.quick else 30

    def estimate(self, trials: int = 1) -> EstimateOptions:
        """The default estimator (pf); fewer particles in quick mode."""
        smc = SMCParams(particles=96) if self.quick else SMCParams()
        return EstimateOptions(trials=trials, seed=self.seed, smc=smc)

    @property
    def task_starts(self) -> int:
        return 2 if self.quick else 6

    @property
    def tour_s(self) -> float:
        return 150.0 if self.quick else 300.0


@dataclass(frozen=True)
class ExperimentEvent:
    """Progress: ``done`` of ``total`` experiments, what runs next; ``results`` on the last event."""

    done: int
    total: int
    label: str
    results: PaperResults | None = None


class _Bench:
    """The experiments' work in progress (private to :func:`run_experiments`)."""

    def __init__(self, opts: PaperOptions) -> None:
        self.opts = opts
        self.learned: dict[str, Learned] = {}
        self.runs: dict[str, list[Run]] = {}
        self.junctions: dict[str, dict[str, str]] = {}


def run_experiments(opts: PaperOptions) -> Iterator[ExperimentEvent]:
    """Run every experiment; yields progress, the last event with the results."""
    for folder in (opts.logs, *opts.logs.parents):
        if folder.exists() and not folder.is_dir():
            raise LfdError(f"cannot write the experiments' logs into {folder}: it is a file")
    try:
        opts.logs.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise LfdError(f"cannot create {opts.logs}: {exc.strerror}") from exc
    b = _Bench(opts)
    stages: list[tuple[str, Callable[[_Bench], None]]] = [
        *((f"demonstrate {s} in tee", _learn_style(s)) for s in STYLES),
        ("run the styles in tee and building", _run_styles),
        ("T-junctions", _run_junctions),
        ("demonstrate the three-goal task", _learn_task),
        ("run the three-goal task", _run_task),
        (f"{opts.trials} estimation trials", _trials),
        ("obstacle passing", _obstacles),
    ]
    for i, (label, stage) in enumerate(stages):
        yield ExperimentEvent(i, len(stages), label)
        stage(b)
    runs = {k: tuple(v) for k, v in b.runs.items()}
    results = PaperResults(
        opts.seed,
        opts.quick,
        opts.trials,
        dict(b.learned),
        runs,
        {k: dict(v) for k, v in b.junctions.items()},
        tuple(style_errors(b.learned, runs)),
    )
    yield ExperimentEvent(len(stages), len(stages), "done", results)


def _learn_style(style: str) -> Callable[[_Bench], None]:
    def stage(b: _Bench) -> None:
        b.learned[style] = ex.demonstrate_and_learn(
            b.opts.logs,
            world="tee",
            legs=(Leg(None, style),),
            name=f"{style}-tee",
            seconds=b.opts.tour_s,
            seed=b.opts.seed,
            estimate=b.opts.estimate(),
        )

    return stage


def _run_styles(b: _Bench) -> None:
    tee, building = load_world("tee"), load_world("building")
    starts = ex.BUILDING_STARTS[:1] if b.opts.quick else ex.BUILDING_STARTS
    secs = 40.0 if b.opts.quick else 90.0
    for style in STYLES:
        table = b.learned[style].table
        b.runs[f"{style}/tee"] = [
            ex.execute(
                b.opts.logs,
                table,
                world=tee,
                start=None,
                seconds=2 * secs,
                name=f"{style}-run-tee",
                label=style,
            )
        ]
        b.runs[f"{style}/building"] = [
            ex.execute(
                b.opts.logs,
                table,
                world=building,
                start=start,
                seconds=secs,
                name=f"{style}-run-building-{j}",
                label=f"{style} from ({start[0]:g}, {start[1]:g})",
            )
            for j, start in enumerate(starts)
        ]


def _run_junctions(b: _Bench) -> None:
    building = load_world("building")
    for style in STYLES:
        table = b.learned[style].table
        choice = {}
        for which, start in (("T", ex.T_JUNCTION), ("rotated T", ex.ROTATED_T)):
            tag = "t" if which == "T" else "rt"
            run = ex.execute(
                b.opts.logs,
                table,
                world=building,
                start=start,
                seconds=40.0,
                name=f"{style}-{tag}",
                label=style,
            )
            b.runs.setdefault(f"junction/{which}", []).append(run)
            choice[which] = junction_choice(run.pose[-1], which)
        b.junctions[style] = choice


def _learn_task(b: _Bench) -> None:
    b.learned["task"] = ex.demonstrate_and_learn(
        b.opts.logs,
        world="building",
        legs=ex.THREE_GOALS,
        name="three-goals",
        seconds=400.0,
        seed=b.opts.seed,
        estimate=b.opts.estimate(),
    )


def _run_task(b: _Bench) -> None:
    building = load_world("building")
    rng = np.random.default_rng(b.opts.seed)
    runs = []
    for k in range(b.opts.task_starts):
        # near the demonstration's start, but not the same (paper Section V-B.1)
        start = (4.0 + rng.uniform(-1.0, 1.0), 1.2 + rng.uniform(-0.35, 0.35), rng.uniform(-0.35, 0.35))
        runs.append(
            ex.execute(
                b.opts.logs,
                b.learned["task"].table,
                world=building,
                start=start,
                seconds=300.0,
                name=f"three-goals-run-{k}",
                label=f"run {k + 1}",
                seed=k,
            )
        )
    b.runs["task"] = runs


def _trials(b: _Bench) -> None:
    path = b.opts.logs / f"three-goals-{b.opts.trials}trials.yaml"
    b.learned["trials"] = ex.relearn(b.learned["task"], estimate=b.opts.estimate(b.opts.trials), out=path)


def _obstacles(b: _Bench) -> None:
    world = load_world("obstacles")
    rng = np.random.default_rng(b.opts.seed + 1000)
    n = 1 if b.opts.quick else 3
    for style in ("pass-left", "pass-right"):
        learned = ex.demonstrate_and_learn(
            b.opts.logs,
            world="obstacles",
            legs=(Leg(None, style),),
            name=f"{style}-obstacles",
            seconds=110.0 if b.opts.quick else 220.0,
            seed=b.opts.seed,
            estimate=b.opts.estimate(),
        )
        b.learned[style] = learned
        b.runs[style] = [
            ex.execute(
                b.opts.logs,
                learned.table,
                world=world,
                start=(1.0, 1.5 + rng.uniform(-0.3, 0.3), rng.uniform(-0.2, 0.2)),
                seconds=90.0,
                name=f"{style}-run-{k}",
                label=f"{style} run {k + 1}",
                seed=k,
            )
            for k in range(n)
        ]
