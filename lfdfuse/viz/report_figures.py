"""The figures of ``lfdfuse report``: each experiment's results drawn as the paper draws them.

Every function here takes the experiments' results (:class:`PaperResults`, nothing is run) and
yields ``(figure, file name, caption)``; :func:`report_figures` chains them in the report's
order. They compose the figure functions of :mod:`lfdfuse.viz.figures`, which draw on an ``Axes``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from lfdfuse.evaluate.paper.records import STYLES, PaperResults, passing_sides, task_order
from lfdfuse.evaluate.plot_data import load_log
from lfdfuse.network.table import table_steps
from lfdfuse.viz import colors, figures
from lfdfuse.viz.plot import DPI, map_figure, table_figure
from lfdfuse.world.model import load_world

STYLE_COLORS = {"keep-left": figures.LEFT_COLOR, "keep-center": "#009E73", "keep-right": figures.RIGHT_COLOR}

#: one drawn figure: the figure, its file name in the report, its caption
Drawn = tuple[Figure, str, str]


def _grid(rows: int, cols: int, width: float, height: float) -> tuple[Figure, Any]:
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    return fig, fig.subplots(rows, cols, squeeze=False)


def demos_tee(res: PaperResults) -> Iterator[Drawn]:
    """Fig. 4 right: the three demonstrations in the small world."""
    tee = load_world("tee")
    fig, axes = _grid(3, 1, 10.0, 10.0)
    for ax, style in zip(axes[:, 0], STYLES, strict=True):
        lr = res.learned[style]
        figures.paths_on_map(
            ax,
            tee,
            [figures.LabelledPath(f"demonstration ({lr.demo_style})", lr.demo_pose, colors.PATH_COLOR)],
            title=f"{style} demonstration in tee ({lr.seconds:.0f} s)",
        )
    yield fig, "fig04-demos-tee.png", "The three demonstrations in the small world (tee, paper Fig. 4 right)."


def styles_tee(res: PaperResults) -> Iterator[Drawn]:
    """Fig. 6: learned styles run in the small world."""
    tee = load_world("tee")
    fig, axes = _grid(3, 1, 10.0, 10.0)
    for ax, style in zip(axes[:, 0], STYLES, strict=True):
        run = res.runs[f"{style}/tee"][0]
        figures.paths_on_map(
            ax,
            tee,
            [figures.LabelledPath(f"{style} network, keeps {run.style}", run.pose, STYLE_COLORS[style])],
            title=f"{style}: learned in tee, run in tee ({run.report['duration_s']:.0f} s)",
        )
    yield fig, "fig06-styles-tee.png", "Learned networks run in the small world (paper Fig. 6)."


def styles_building(res: PaperResults) -> Iterator[Drawn]:
    """Fig. 9: the same networks in the large world."""
    building = load_world("building")
    fig, axes = _grid(1, 3, 16.0, 6.0)
    for ax, style in zip(axes[0], STYLES, strict=True):
        runs = res.runs[f"{style}/building"]
        figures.paths_on_map(
            ax,
            building,
            [
                figures.LabelledPath(f"{r.label}: {r.style}", r.pose, colors.step_color(i))
                for i, r in enumerate(runs)
            ],
            title=f"{style} (learned in tee) in building",
        )
    yield (
        fig,
        "fig09-styles-building.png",
        "Networks learned in tee run in the large world (paper Figs. 9, Scenario 2).",
    )


def junctions(res: PaperResults) -> Iterator[Drawn]:
    """Fig. 7: the turn taken at a T and a rotated T."""
    building = load_world("building")
    fig, axes = _grid(1, 2, 12.0, 6.0)
    for ax, which, (x0, x1, y0, y1) in zip(
        axes[0], ("T", "rotated T"), ((12.0, 28.0, 14.0, 30.5), (30.0, 40.5, 2.0, 22.0)), strict=True
    ):
        paths = [
            figures.LabelledPath(f"{r.label}: {res.junctions[r.label][which]}", r.pose, STYLE_COLORS[r.label])
            for r in res.runs[f"junction/{which}"]
        ]
        figures.paths_on_map(ax, building, paths, title=f"{which} junction")
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
    yield fig, "fig07-junctions.png", "The style decides the turn at a T and a rotated T (paper Fig. 7)."


def side_measures(res: PaperResults) -> Iterator[Drawn]:
    """Figs. 10 and 11: the range-to-wall style measure, and the learned style's error."""
    side = [
        figures.SideRanges(f"{s}\ndemo tee", res.learned[s].demo_left_m, res.learned[s].demo_right_m)
        for s in STYLES
    ]
    for s in STYLES:
        for where in ("tee", "building"):
            runs = res.runs[f"{s}/{where}"]
            side.append(
                figures.SideRanges(
                    f"{s}\nrun {where}",
                    float(np.mean([r.report["left_range_mean_m"] for r in runs])),
                    float(np.mean([r.report["right_range_mean_m"] for r in runs])),
                )
            )
    fig, axes = _grid(1, 1, 12.0, 5.5)
    figures.side_ranges(axes[0, 0], side)
    yield fig, "fig10-side-ranges.png", "Mean laser range to the left and right walls (paper Fig. 10)."
    fig, axes = _grid(1, 2, 14.0, 5.5)
    figures.side_errors(axes[0, 0], list(res.style_errors))
    run = res.runs["keep-left/building"][0]
    t = np.arange(len(run.left_m)) * 0.1
    figures.side_profile(axes[0, 1], t, run.left_m, run.right_m, title=f"{run.label} in building, over time")
    yield (
        fig,
        "fig11-style-error.png",
        "Left: how far the learned style is from the demonstrated one — median distance to each wall where both "
        "are within 2 m, runs minus demonstration (paper Fig. 11 left). Right: the ±90° ranges of one run over "
        "time (Fig. 11 right).",
    )


def task(res: PaperResults) -> Iterator[Drawn]:
    """Fig. 8: the three-goal task's demonstration, one run, and all runs."""
    yield (
        map_figure(
            load_log(res.learned["task"].segmented), title="three-goal demonstration, by goal segment"
        ),
        "fig08-task-demo.png",
        "The three-goal demonstration: left to red, centre to green, right to blue (paper Fig. 8).",
    )
    task_runs = res.runs["task"]
    yield (
        map_figure(
            load_log(task_runs[0].log), title=f"three-goal task, {task_runs[0].label}, by network step"
        ),
        "fig08-task-run.png",
        "One run of the learned three-goal network, coloured by network step.",
    )
    fig, axes = _grid(1, 1, 10.0, 8.0)
    figures.paths_on_map(
        axes[0, 0],
        load_world("building"),
        [
            figures.LabelledPath(
                f"{r.label}: {' → '.join(task_order(r.report)) or 'no goal'}",
                r.pose,
                colors.step_color(i),
                bool(r.report["completed"]),
            )
            for i, r in enumerate(task_runs)
        ],
        title=f"three-goal task from {len(task_runs)} starts",
    )
    yield fig, "fig11-task-runs.png", "The learned task from several starts (paper Section V-B.1)."


def weights(res: PaperResults) -> Iterator[Drawn]:
    """Figs. 12-14: the weights over trials, one figure per goal, and the posterior std."""
    trials = res.learned["trials"].table
    for k, step in enumerate(table_steps(trials)[:3]):
        fig = Figure(figsize=(max(10.0, 1.0 * len(step.rows) + 2), 5.0), dpi=DPI, layout="constrained")
        ax = fig.add_subplot()
        drawn = figures.weight_bars(
            ax,
            step,
            trials.behaviors,
            spread="trial_std",
            title=f"goal {k + 1} ({step.goal}): mean weight over {res.trials} trials, whiskers 1 std",
        )
        fig.legend(
            handles=figures.behavior_legend_handles([b for b in trials.behaviors if b in drawn]),
            loc="outside right upper",
            fontsize=8,
            frameon=False,
        )
        yield (
            fig,
            f"fig{12 + k}-weights-goal{k + 1}.png",
            f"Fusion weights for goal {k + 1} over {res.trials} trials (paper Fig. {12 + k}).",
        )
    yield (
        table_figure(
            trials, spread="std", title="three-goal table: posterior std (what the data leaves open)"
        ),
        "fig12-14-posterior.png",
        "The same rows with the posterior std instead of the spread over trials (our addition).",
    )


def obstacles(res: PaperResults) -> Iterator[Drawn]:
    """Fig. 15: obstacle passing on the demonstrated side."""
    world = load_world("obstacles")
    fig, axes = _grid(2, 1, 10.0, 6.0)
    centres = [(ob.circle[0], ob.circle[1]) for ob in world.obstacles if ob.circle]
    for ax, style in zip(axes[:, 0], ("pass-left", "pass-right"), strict=True):
        paths = [
            figures.LabelledPath(
                f"{r.label}: passed {', '.join(passing_sides(r.pose, centres)) or 'none'}",
                r.pose,
                colors.step_color(i),
            )
            for i, r in enumerate(res.runs[style])
        ]
        figures.paths_on_map(ax, world, paths, title=f"{style} network")
    yield fig, "fig15-obstacles.png", "Obstacle passing on the demonstrated side (paper Fig. 15)."


#: the report's figures, in its order
FIGURES: tuple[Callable[[PaperResults], Iterator[Drawn]], ...] = (
    demos_tee,
    styles_tee,
    styles_building,
    junctions,
    side_measures,
    task,
    weights,
    obstacles,
)


def report_figures(res: PaperResults) -> Iterator[Drawn]:
    """Every figure of the report, in order."""
    for draw in FIGURES:
        yield from draw(res)
