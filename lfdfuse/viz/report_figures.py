"""The figures of ``lfdfuse report``: each experiment's results drawn as the paper draws them.

:func:`draw_figures` is the report's last stage (:mod:`lfdfuse.viz.report` runs the experiments);
it composes the figure functions of :mod:`lfdfuse.viz.figures` and saves each PNG with a caption.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure

from lfdfuse.viz import colors, compare, experiments, figures
from lfdfuse.viz.load import load_log, table_steps
from lfdfuse.viz.plot import DPI, map_figure, table_figure
from lfdfuse.world.model import load_world

if TYPE_CHECKING:
    from lfdfuse.viz.report import _State

STYLES = ("keep-left", "keep-center", "keep-right")
STYLE_COLORS = {"keep-left": figures.LEFT_COLOR, "keep-center": "#009E73", "keep-right": figures.RIGHT_COLOR}


def _grid(rows: int, cols: int, width: float, height: float) -> tuple[Figure, Any]:
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    return fig, fig.subplots(rows, cols, squeeze=False)


def draw_figures(st: _State) -> None:
    """Every figure of the report from the experiments' results in ``st``."""
    tee, building, obstacles = load_world("tee"), load_world("building"), load_world("obstacles")
    # Fig. 4 right / demos: the three demonstrations in the small world
    fig, axes = _grid(3, 1, 10.0, 10.0)
    for ax, style in zip(axes[:, 0], STYLES, strict=True):
        lr = st.learned[style]
        figures.paths_on_map(
            ax,
            tee,
            [figures.LabelledPath(f"demonstration ({lr.demo_style})", lr.demo_pose, colors.PATH_COLOR)],
            title=f"{style} demonstration in tee ({lr.seconds:.0f} s)",
        )
    st.figure(
        fig, "fig04-demos-tee.png", "The three demonstrations in the small world (tee, paper Fig. 4 right)."
    )
    # Fig. 6: learned styles run in the small world
    fig, axes = _grid(3, 1, 10.0, 10.0)
    for ax, style in zip(axes[:, 0], STYLES, strict=True):
        run = st.runs[f"{style}/tee"][0]
        figures.paths_on_map(
            ax,
            tee,
            [figures.LabelledPath(f"{style} network, keeps {run.style}", run.pose, STYLE_COLORS[style])],
            title=f"{style}: learned in tee, run in tee ({run.report['duration_s']:.0f} s)",
        )
    st.figure(fig, "fig06-styles-tee.png", "Learned networks run in the small world (paper Fig. 6).")
    # Fig. 9: the same networks in the large world
    fig, axes = _grid(1, 3, 16.0, 6.0)
    for ax, style in zip(axes[0], STYLES, strict=True):
        runs = st.runs[f"{style}/building"]
        figures.paths_on_map(
            ax,
            building,
            [
                figures.LabelledPath(f"{r.label}: {r.style}", r.pose, colors.step_color(i))
                for i, r in enumerate(runs)
            ],
            title=f"{style} (learned in tee) in building",
        )
    st.figure(
        fig,
        "fig09-styles-building.png",
        "Networks learned in tee run in the large world (paper Figs. 9, Scenario 2).",
    )
    # Fig. 7: T-junction choices
    fig, axes = _grid(1, 2, 12.0, 6.0)
    for ax, which, (x0, x1, y0, y1) in zip(
        axes[0], ("T", "rotated T"), ((12.0, 28.0, 14.0, 30.5), (30.0, 40.5, 2.0, 22.0)), strict=True
    ):
        paths = [
            figures.LabelledPath(f"{r.label}: {st.junctions[r.label][which]}", r.pose, STYLE_COLORS[r.label])
            for r in st.runs[f"junction/{which}"]
        ]
        figures.paths_on_map(ax, building, paths, title=f"{which} junction")
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
    st.figure(fig, "fig07-junctions.png", "The style decides the turn at a T and a rotated T (paper Fig. 7).")
    # Fig. 10 and 11: the range-to-wall style measure
    side = [
        figures.SideRanges(f"{s}\ndemo tee", st.learned[s].demo_left_m, st.learned[s].demo_right_m)
        for s in STYLES
    ]
    for s in STYLES:
        for where in ("tee", "building"):
            runs = st.runs[f"{s}/{where}"]
            side.append(
                figures.SideRanges(
                    f"{s}\nrun {where}",
                    float(np.mean([r.report["left_range_mean_m"] for r in runs])),
                    float(np.mean([r.report["right_range_mean_m"] for r in runs])),
                )
            )
    fig, axes = _grid(1, 1, 12.0, 5.5)
    figures.side_ranges(axes[0, 0], side)
    st.figure(fig, "fig10-side-ranges.png", "Mean laser range to the left and right walls (paper Fig. 10).")
    fig, axes = _grid(1, 2, 14.0, 5.5)
    st.errors = compare.style_errors(st.learned, st.runs)
    figures.side_errors(axes[0, 0], st.errors)
    run = st.runs["keep-left/building"][0]
    t = np.arange(len(run.left_m)) * 0.1
    figures.side_profile(axes[0, 1], t, run.left_m, run.right_m, title=f"{run.label} in building, over time")
    st.figure(
        fig,
        "fig11-style-error.png",
        "Left: how far the learned style is from the demonstrated one — median distance to each wall where both "
        "are within 2 m, runs minus demonstration (paper Fig. 11 left). Right: the ±90° ranges of one run over "
        "time (Fig. 11 right).",
    )
    # Fig. 8: the three-goal task: demonstration, one run, all runs
    st.figure(
        map_figure(load_log(st.learned["task"].segmented), title="three-goal demonstration, by goal segment"),
        "fig08-task-demo.png",
        "The three-goal demonstration: left to red, centre to green, right to blue (paper Fig. 8).",
    )
    task_runs = st.runs["task"]
    st.figure(
        map_figure(
            load_log(task_runs[0].log), title=f"three-goal task, {task_runs[0].label}, by network step"
        ),
        "fig08-task-run.png",
        "One run of the learned three-goal network, coloured by network step.",
    )
    fig, axes = _grid(1, 1, 10.0, 8.0)
    figures.paths_on_map(
        axes[0, 0],
        building,
        [
            figures.LabelledPath(
                f"{r.label}: {' → '.join(experiments.task_order(r.report)) or 'no goal'}",
                r.pose,
                colors.step_color(i),
                bool(r.report["completed"]),
            )
            for i, r in enumerate(task_runs)
        ],
        title=f"three-goal task from {len(task_runs)} starts",
    )
    st.figure(fig, "fig11-task-runs.png", "The learned task from several starts (paper Section V-B.1).")
    # Figs. 12-14: weights over trials, one figure per goal
    trials = st.learned["trials"].table
    for k, step in enumerate(table_steps(trials)[:3]):
        fig = Figure(figsize=(max(10.0, 1.0 * len(step.rows) + 2), 5.0), dpi=DPI, layout="constrained")
        ax = fig.add_subplot()
        drawn = figures.weight_bars(
            ax,
            step,
            trials.behaviors,
            spread="trial_std",
            title=f"goal {k + 1} ({step.goal}): mean weight over {st.opts.trials} trials, whiskers 1 std",
        )
        fig.legend(
            handles=figures.behavior_legend_handles([b for b in trials.behaviors if b in drawn]),
            loc="outside right upper",
            fontsize=8,
            frameon=False,
        )
        st.figure(
            fig,
            f"fig{12 + k}-weights-goal{k + 1}.png",
            f"Fusion weights for goal {k + 1} over {st.opts.trials} trials (paper Fig. {12 + k}).",
        )
    st.figure(
        table_figure(
            trials, spread="std", title="three-goal table: posterior std (what the data leaves open)"
        ),
        "fig12-14-posterior.png",
        "The same rows with the posterior std instead of the spread over trials (our addition).",
    )
    # Fig. 15: obstacles
    fig, axes = _grid(2, 1, 10.0, 6.0)
    centres = [(ob.circle[0], ob.circle[1]) for ob in obstacles.obstacles if ob.circle]
    for ax, style in zip(axes[:, 0], ("pass-left", "pass-right"), strict=True):
        paths = [
            figures.LabelledPath(
                f"{r.label}: passed {', '.join(experiments.passing_sides(r.pose, centres)) or 'none'}",
                r.pose,
                colors.step_color(i),
            )
            for i, r in enumerate(st.runs[style])
        ]
        figures.paths_on_map(ax, obstacles, paths, title=f"{style} network")
    st.figure(fig, "fig15-obstacles.png", "Obstacle passing on the demonstrated side (paper Fig. 15).")
