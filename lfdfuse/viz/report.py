"""``lfdfuse report``: the paper's experiments rerun, drawn, and set beside the paper's results.

:func:`run_report` is an iterator of :class:`ReportEvent` (the CLI turns them into a progress
bar); its last event carries the :class:`ReportResult`. It writes ``DIR/index.html``, one PNG
per figure, ``DIR/report.json`` with every number, and the logs and tables behind them in
``DIR/logs/`` (open them in Foxglove). The comparison rows are built in
:mod:`lfdfuse.viz.compare`; every number in them is measured in this run.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from lfdfuse.errors import LfdError
from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.files import write_text_atomic
from lfdfuse.network.table import write_table
from lfdfuse.segment.read import read_segmented
from lfdfuse.sources.tasks import Leg
from lfdfuse.viz import compare, experiments
from lfdfuse.viz.experiments import Learned, Run
from lfdfuse.viz.html import write_index
from lfdfuse.viz.plot import save_figure
from lfdfuse.viz.report_figures import STYLES, draw_figures
from lfdfuse.world.model import load_world


@dataclass(frozen=True)
class ReportOptions:
    """``quick``: shorter demonstrations and runs, fewer starts and trials (a smoke test, ~30 s)."""

    out: Path
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
class ReportFigure:
    file: str
    caption: str


@dataclass(frozen=True)
class ReportResult:
    out: str
    figures: tuple[ReportFigure, ...]
    comparison: tuple[compare.Row, ...]
    numbers: dict[str, Any]


@dataclass(frozen=True)
class ReportEvent:
    """Progress: ``done`` of ``total`` stages, what runs next; ``result`` on the last event."""

    done: int
    total: int
    label: str
    result: ReportResult | None = None


@dataclass
class _State:
    opts: ReportOptions
    logs: Path
    learned: dict[str, Learned] = field(default_factory=dict)
    runs: dict[str, list[Run]] = field(default_factory=dict)
    junctions: dict[str, dict[str, str]] = field(default_factory=dict)
    errors: list[tuple[str, float, float]] = field(default_factory=list)
    figures: list[ReportFigure] = field(default_factory=list)

    def figure(self, fig: Figure, name: str, caption: str) -> None:
        save_figure(fig, self.opts.out / name)
        self.figures.append(ReportFigure(name, caption))


def run_report(opts: ReportOptions) -> Iterator[ReportEvent]:
    """Run every experiment, write the report; yields progress, the last event with the result."""
    if opts.out.exists() and not opts.out.is_dir():
        raise LfdError(f"cannot write the report to {opts.out}: it is a file")
    logs = opts.out / "logs"
    try:
        logs.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise LfdError(f"cannot create {logs}: {exc.strerror}") from exc
    st = _State(opts, logs)
    stages: list[tuple[str, Callable[[_State], None]]] = [
        *((f"demonstrate {s} in tee", _learn_style(s)) for s in STYLES),
        ("run the styles in tee and building", _run_styles),
        ("T-junctions", _run_junctions),
        ("demonstrate the three-goal task", _learn_task),
        ("run the three-goal task", _run_task),
        (f"{opts.trials} estimation trials", _trials),
        ("obstacle passing", _obstacles),
        ("figures", draw_figures),
    ]
    for i, (label, stage) in enumerate(stages):
        yield ReportEvent(i, len(stages), label)
        stage(st)
    rows = tuple(compare.rows(st.learned, st.runs, st.junctions, st.errors, quick=opts.quick))
    numbers = _numbers(st, rows)
    write_text_atomic(opts.out / "report.json", json.dumps(numbers, indent=1, allow_nan=False) + "\n")
    write_index(opts.out / "index.html", figures=st.figures, rows=rows, numbers=numbers)
    result = ReportResult(str(opts.out), tuple(st.figures), rows, numbers)
    yield ReportEvent(len(stages), len(stages), "done", result)


# ------------------------------------------------------------------------------ stages


def _learn_style(style: str) -> Callable[[_State], None]:
    def stage(st: _State) -> None:
        st.learned[style] = experiments.learn(
            st.logs,
            world="tee",
            legs=(Leg(None, style),),
            name=f"{style}-tee",
            seconds=st.opts.tour_s,
            seed=st.opts.seed,
            estimate=st.opts.estimate(),
        )

    return stage


def _run_styles(st: _State) -> None:
    tee, building = load_world("tee"), load_world("building")
    starts = experiments.BUILDING_STARTS[:1] if st.opts.quick else experiments.BUILDING_STARTS
    secs = 40.0 if st.opts.quick else 90.0
    for style in STYLES:
        table = st.learned[style].table
        st.runs[f"{style}/tee"] = [
            experiments.execute(
                st.logs, table, world=tee, start=None, seconds=2 * secs, name=f"{style}-run-tee", label=style
            )
        ]
        st.runs[f"{style}/building"] = [
            experiments.execute(
                st.logs,
                table,
                world=building,
                start=start,
                seconds=secs,
                name=f"{style}-run-building-{j}",
                label=f"{style} from ({start[0]:g}, {start[1]:g})",
            )
            for j, start in enumerate(starts)
        ]


def _run_junctions(st: _State) -> None:
    building = load_world("building")
    for style in STYLES:
        table = st.learned[style].table
        choice = {}
        for which, start in (("T", experiments.T_JUNCTION), ("rotated T", experiments.ROTATED_T)):
            tag = "t" if which == "T" else "rt"
            run = experiments.execute(
                st.logs, table, world=building, start=start, seconds=40.0, name=f"{style}-{tag}", label=style
            )
            st.runs.setdefault(f"junction/{which}", []).append(run)
            choice[which] = experiments.junction_choice(run.pose[-1], which)
        st.junctions[style] = choice


def _learn_task(st: _State) -> None:
    st.learned["task"] = experiments.learn(
        st.logs,
        world="building",
        legs=experiments.THREE_GOALS,
        name="three-goals",
        seconds=400.0,
        seed=st.opts.seed,
        estimate=st.opts.estimate(),
    )


def _run_task(st: _State) -> None:
    building = load_world("building")
    rng = np.random.default_rng(st.opts.seed)
    runs = []
    for k in range(st.opts.task_starts):
        # near the demonstration's start, but not the same (paper Section V-B.1)
        start = (4.0 + rng.uniform(-1.0, 1.0), 1.2 + rng.uniform(-0.35, 0.35), rng.uniform(-0.35, 0.35))
        runs.append(
            experiments.execute(
                st.logs,
                st.learned["task"].table,
                world=building,
                start=start,
                seconds=300.0,
                name=f"three-goals-run-{k}",
                label=f"run {k + 1}",
                seed=k,
            )
        )
    st.runs["task"] = runs


def _trials(st: _State) -> None:
    learned = st.learned["task"]
    table, _, _ = estimate_run(
        read_segmented(learned.segmented),
        opts=st.opts.estimate(st.opts.trials),
        name=learned.segmented.name,
    )
    path = st.logs / f"three-goals-{st.opts.trials}trials.yaml"
    write_table(table, path)
    st.learned["trials"] = replace(learned, table_path=path, table=table)


def _obstacles(st: _State) -> None:
    world = load_world("obstacles")
    rng = np.random.default_rng(st.opts.seed + 1000)
    n = 1 if st.opts.quick else 3
    for style in ("pass-left", "pass-right"):
        learned = experiments.learn(
            st.logs,
            world="obstacles",
            legs=(Leg(None, style),),
            name=f"{style}-obstacles",
            seconds=110.0 if st.opts.quick else 220.0,
            seed=st.opts.seed,
            estimate=st.opts.estimate(),
        )
        st.learned[style] = learned
        st.runs[style] = [
            experiments.execute(
                st.logs,
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


def _numbers(st: _State, rows: tuple[compare.Row, ...]) -> dict[str, Any]:
    def clean(x: Any) -> Any:
        if isinstance(x, float):
            return None if not math.isfinite(x) else round(x, 4)
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        return x

    learned = {
        k: {
            "style": v.style,
            "world": v.world,
            "demo": v.demo.name,
            "table": v.table_path.name,
            "seconds": v.seconds,
            "demo_left_range_mean_m": v.demo_left_m,
            "demo_right_range_mean_m": v.demo_right_m,
            "demo_style": v.demo_style,
        }
        for k, v in st.learned.items()
    }
    return clean(
        {
            "format": "lfdfuse/paper-report@1",
            "seed": st.opts.seed,
            "quick": st.opts.quick,
            "trials": st.opts.trials,
            "comparison": [r.as_dict() for r in rows],
            "learned": learned,
            "runs": {k: [r.summary() for r in v] for k, v in st.runs.items()},
            "junctions": st.junctions,
            "weights": compare.weight_stats(st.learned["trials"].table),
            "figures": [{"file": f.file, "caption": f.caption} for f in st.figures],
        }
    )
