"""The figures, gallery style: one function per figure, taking data and an ``Axes``.

Nothing here reads files or decides sizes; :mod:`lfdfuse.viz.plot` and :mod:`lfdfuse.viz.report`
compose these on figures. Lengths are metres, times seconds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib import patheffects
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Polygon

from lfdfuse.evaluate.plot_data import PERSON_PART, PathData
from lfdfuse.network.table import StepRows
from lfdfuse.viz import colors
from lfdfuse.world.parse import World

LEFT_COLOR = "#0072B2"
RIGHT_COLOR = "#D55E00"


def draw_world(
    ax: Axes, world: World, *, margin_m: float = 0.5, clear_of: Sequence[tuple[float, float]] = ()
) -> None:
    """Walls (black), obstacles (brown, filled) and targets (their colour, named), to scale.

    A target's name is written on the side away from the nearest of ``clear_of`` (x, y in m:
    the marks drawn beside targets, such as where a goal was reached), so it never sits on them.
    """
    for line in world.walls:
        xy = np.asarray(line)
        ax.plot(xy[:, 0], xy[:, 1], color=colors.WALL_COLOR, lw=2.0, solid_capstyle="round", zorder=2)
    for ob in world.obstacles:
        poly = np.asarray(ob.polygon().exterior.coords)
        ax.add_patch(
            Polygon(poly, closed=True, fc=colors.OBSTACLE_COLOR, ec=colors.WALL_COLOR, lw=1, zorder=2)
        )
    for t in world.targets:
        c = colors.target_color(t.name)
        ax.add_patch(Circle((t.x, t.y), max(t.radius, 0.25), fc=c, ec="black", lw=0.8, zorder=4))
        dx, dy = _away(t.x, t.y, clear_of)
        ax.annotate(
            t.name,
            (t.x, t.y),
            xytext=(LABEL_OFFSET_PT * dx, LABEL_OFFSET_PT * dy),
            textcoords="offset points",
            ha="left" if dx >= 0.0 else "right",
            va="bottom" if dy >= 0.0 else "top",
            color=c,
            fontsize=9,
            weight="bold",
            zorder=8,
            path_effects=[patheffects.withStroke(linewidth=2.5, foreground="white")],
        )
    x0, y0, x1, y1 = world.bounds()
    ax.set_xlim(x0 - margin_m, x1 + margin_m)
    ax.set_ylim(y0 - margin_m, y1 + margin_m)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


#: how far a target's name sits from its centre (points): past the target and a goal star's size
LABEL_OFFSET_PT = 13.0


def _away(x: float, y: float, marks: Sequence[tuple[float, float]]) -> tuple[float, float]:
    """The unit direction from the nearest mark to ``(x, y)``: up and right when no mark is near."""
    near = [(mx, my) for mx, my in marks if math.hypot(x - mx, y - my) < 3.0]
    if not near:
        return (math.sqrt(0.5), math.sqrt(0.5))
    mx, my = min(near, key=lambda m: math.hypot(x - m[0], y - m[1]))
    d = math.hypot(x - mx, y - my)
    if d < 1e-9:  # the mark on the target itself: keep the label up and to the right of it
        return (math.sqrt(0.5), math.sqrt(0.5))
    return ((x - mx) / d, (y - my) / d)


def _runs(part: np.ndarray) -> list[tuple[int, int, int]]:
    """``(start, stop, value)`` of each stretch of equal values."""
    if len(part) == 0:
        return []
    cut = np.nonzero(part[1:] != part[:-1])[0] + 1
    edges = [0, *cut.tolist(), len(part)]
    return [(a, b, int(part[a])) for a, b in zip(edges[:-1], edges[1:], strict=True)]


def _ticks(pose: np.ndarray, idx: np.ndarray, half_m: float) -> np.ndarray:
    """Short segments across the path at ``idx``: ``(n, 2, 2)``."""
    p = pose[idx]
    nx, ny = -np.sin(p[:, 2]), np.cos(p[:, 2])
    a = np.column_stack([p[:, 0] - half_m * nx, p[:, 1] - half_m * ny])
    b = np.column_stack([p[:, 0] + half_m * nx, p[:, 1] + half_m * ny])
    return np.stack([a, b], axis=1)


def draw_path(ax: Axes, data: PathData, *, bac_ticks: bool = True, lw: float = 2.0) -> None:
    """The path coloured by goal segment or network step, the start, goals reached, BAC changes
    (ticks across the path) and collisions; every mark labelled for a legend."""
    x, y = data.pose[:, 0], data.pose[:, 1]
    labelled: set[int] = set()
    for a, b, j in _runs(data.part):
        if j < 0 and b - a < 3:
            continue  # the tick or two after the last goal
        if j < 0:
            color, label = colors.UNKNOWN_COLOR, "after the last goal"
        elif data.kind == "demo" or data.part_names[j] == PERSON_PART:
            color = colors.PATH_COLOR if data.kind == "demo" else colors.step_color(j)
            label = data.part_names[j]
        else:
            color, label = colors.step_color(j), f"{data.part_label} {data.part_names[j]}"
        ax.plot(
            x[a : b + 1],
            y[a : b + 1],
            color=color,
            lw=lw,
            zorder=3,
            label=None if j in labelled else label,
        )
        labelled.add(j)
    changes = data.bac_changes()
    if bac_ticks and len(changes):
        ax.add_collection(
            LineCollection(
                list(_ticks(data.pose, changes, 0.18)),
                colors="#333333",
                linewidths=0.9,
                zorder=3.5,
                label=f"BAC change ({len(changes)})",
            )
        )
    x0, y0, th0 = data.pose[0]
    ax.plot([x0], [y0], "o", ms=9, mfc="white", mec="black", mew=1.5, zorder=5, label="start")
    ax.annotate(
        "",
        xy=(x0 + 0.9 * math.cos(th0), y0 + 0.9 * math.sin(th0)),
        xytext=(x0, y0),
        arrowprops={"arrowstyle": "-|>", "color": "black", "lw": 1.2},
        zorder=5,
    )
    xe, ye = data.pose[-1, :2]
    ax.plot([xe], [ye], "s", ms=8, mfc="black", mec="black", zorder=5, label="end")
    for g in data.goals:
        ax.plot(
            [g.x],
            [g.y],
            "*",
            ms=16,
            mfc=colors.target_color(g.target),
            mec="black",
            zorder=6,
            label=f"reached {g.target} at {g.t_s:.0f} s",
        )
    if len(data.collisions):
        hits = data.pose[data.collisions]
        ax.plot(
            hits[:, 0],
            hits[:, 1],
            "X",
            ms=10,
            mfc=colors.COLLISION_COLOR,
            mec="black",
            zorder=7,
            label=f"collision ({len(hits)})",
        )


#: the finest cell of a scan occupancy image (m), and the most cells along its longer side
SCAN_CELL_M = 0.05
SCAN_MAX_CELLS = 1600
SCAN_COLOR = "#5a5a5a"


def scan_extent(points: np.ndarray, keep: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The corners ``(2,), (2,)`` (m) of the view of ``points (K, 2)``, K > 0: all but the
    farthest 0.2 % on each side (stray returns), with ``keep (M, 2)``, and a metre around."""
    lo = np.percentile(points, 0.2, axis=0) - 1.0
    hi = np.percentile(points, 99.8, axis=0) + 1.0
    if keep is not None and len(keep):
        lo, hi = np.minimum(lo, keep.min(axis=0) - 1.0), np.maximum(hi, keep.max(axis=0) + 1.0)
    return lo, hi


def draw_scans(ax: Axes, points: np.ndarray, *, keep: np.ndarray | None = None) -> int:
    """Where the laser hit, as an occupancy image: cells of at least :data:`SCAN_CELL_M` holding
    any of ``points (K, 2)`` (m) in grey, darker the more returns fell in them. The view spans
    the points (less the farthest 0.2 % on each side: stray returns) and ``keep (M, 2)``.

    Returns the number of occupied cells (0: nothing drawn).
    """
    if len(points) == 0:
        return 0
    lo, hi = scan_extent(points, keep)
    cell = max(SCAN_CELL_M, float((hi - lo).max()) / SCAN_MAX_CELLS)
    nx, ny = (np.ceil((hi - lo) / cell).astype(int) + 1).tolist()
    counts, _, _ = np.histogram2d(
        points[:, 0],
        points[:, 1],
        bins=(nx, ny),
        range=((lo[0], lo[0] + nx * cell), (lo[1], lo[1] + ny * cell)),
    )
    occupied = int((counts > 0).sum())
    if occupied == 0:
        return 0
    # grey level by log(returns): a wall seen in every scan is dark, a passing leg faint
    shade = np.log1p(counts.T) / max(float(np.log1p(counts.max())), 1e-9)
    rgba = np.zeros((*shade.shape, 4))
    rgba[..., :3] = np.array([int(SCAN_COLOR[i : i + 2], 16) / 255.0 for i in (1, 3, 5)])
    rgba[..., 3] = np.where(counts.T > 0, 0.25 + 0.75 * shade, 0.0)
    ax.imshow(
        rgba,
        origin="lower",
        extent=(lo[0], lo[0] + nx * cell, lo[1], lo[1] + ny * cell),
        interpolation="nearest",
        zorder=1,
    )
    ax.plot([], [], "s", ms=6, color=SCAN_COLOR, label="laser returns (odometry frame)")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    return occupied


def log_map(ax: Axes, data: PathData, *, title: str | None = None) -> None:
    """A log on its map: world, path, marks, a title with what it is and how long it ran. A log
    without a map draws the scans' returns instead (:func:`draw_scans`), so a real run reads."""
    scanned = 0
    if data.world is not None:
        draw_world(ax, data.world, clear_of=[(g.x, g.y) for g in data.goals])
    else:
        if data.scan_points is not None:
            scanned = draw_scans(ax, data.scan_points, keep=data.pose[:, :2])
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    draw_path(ax, data)
    if data.world is None and not scanned:
        ax.autoscale_view()
    duration = float(data.t_s[-1]) if len(data.t_s) else 0.0
    if data.world is not None:
        where = data.world.name
    elif scanned:
        where = f"no map: {len(data.scan_points) if data.scan_points is not None else 0} laser returns"
    else:
        where = "no map in the log"
    ax.set_title(title or f"{data.kind} — {where}, {duration:.0f} s", loc="left")
    ax.grid(True, lw=0.3, alpha=0.5)


# ------------------------------------------------------------------------------ weights


def weight_bars(
    ax: Axes,
    step: StepRows,
    behaviors: Sequence[str],
    *,
    spread: str = "std",
    title: str | None = None,
) -> list[str]:
    """One group of bars per BAC row (the paper's Figs. 12–14): the weight of each applicable
    behaviour in its fixed colour, whiskers of ``spread`` (``std``: the posterior std;
    ``trial_std``: the spread over trials), the BAC and its sample count under each group.

    Returns the behaviours drawn (for a shared legend).
    """
    order = {b: i for i, b in enumerate(behaviors)}
    drawn: list[str] = []
    labels: list[str] = []
    for g, row in enumerate(step.rows):
        names = sorted(row.weights, key=lambda n: order.get(n, len(order)))
        sd = row.trial_std if spread == "trial_std" else row.std
        width = 0.8 / max(len(names), 1)
        for k, n in enumerate(names):
            xc = g - 0.4 + width * (k + 0.5)
            err = None if sd is None else [[0.0], [sd.get(n, 0.0)]]
            ax.bar(
                xc,
                row.weights[n],
                width * 0.92,
                color=colors.behavior_color(n),
                hatch=colors.behavior_hatch(n),
                edgecolor="black",
                linewidth=0.4,
                yerr=err,
                error_kw={"elinewidth": 1.0, "capsize": 2.0, "ecolor": "black"},
                zorder=2,
            )
            if n not in drawn:
                drawn.append(n)
        n_txt = "n=?" if row.samples is None else f"n={row.samples}"
        flag = "\nnot identif." if row.identifiable is False else ""
        labels.append(f"{row.bac}\n{n_txt}{flag}")
    ax.set_xticks(range(len(step.rows)), labels, fontsize=8)
    ax.set_xlim(-0.6, max(len(step.rows), 1) - 0.4)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("weight")
    ax.grid(True, axis="y", lw=0.3, alpha=0.6, zorder=0)
    goal = f" (goal: {step.goal})" if step.goal else " (no goal)"
    what = "std over trials" if spread == "trial_std" else "posterior std"
    ax.set_title(title or f"step {step.name}{goal} — whiskers: {what}; BAC and samples below", loc="left")
    if not step.rows:
        ax.text(0.5, 0.5, "no rows", transform=ax.transAxes, ha="center", va="center")
    return drawn


def behavior_legend_handles(names: Sequence[str]) -> list[Patch]:
    return [
        Patch(
            fc=colors.behavior_color(n),
            hatch=colors.behavior_hatch(n),
            ec="black",
            lw=0.4,
            label=colors.behavior_label(n),
        )
        for n in names
    ]


# ------------------------------------------------------------------------------ the paper's measures


@dataclass(frozen=True)
class SideRanges:
    """The paper's style measure of one run (Fig. 10): mean laser range at +90° and −90° (m)."""

    label: str
    left_m: float
    right_m: float


def side_ranges(ax: Axes, rows: Sequence[SideRanges], *, title: str | None = None) -> None:
    """Paired bars per run: mean distance to the left and to the right wall."""
    x = np.arange(len(rows))
    ax.bar(x - 0.2, [r.left_m for r in rows], 0.38, color=LEFT_COLOR, label="left (+90°)", zorder=2)
    ax.bar(x + 0.2, [r.right_m for r in rows], 0.38, color=RIGHT_COLOR, label="right (−90°)", zorder=2)
    ax.set_xticks(x, [r.label for r in rows], fontsize=8)
    ax.set_ylabel("mean laser range (m)")
    ax.grid(True, axis="y", lw=0.3, alpha=0.6, zorder=0)
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(title or "distance to the left and right walls (paper Fig. 10)", loc="left")


def side_errors(ax: Axes, rows: Sequence[tuple[str, float, float]], *, title: str | None = None) -> None:
    """``(label, left error, right error)`` in metres: run minus demonstration (paper Fig. 11 left)."""
    x = np.arange(len(rows))
    ax.bar(x - 0.2, [r[1] for r in rows], 0.38, color=LEFT_COLOR, label="left wall", zorder=2)
    ax.bar(x + 0.2, [r[2] for r in rows], 0.38, color=RIGHT_COLOR, label="right wall", zorder=2)
    ax.axhline(0.0, color="black", lw=0.8)
    ax.set_xticks(x, [r[0] for r in rows], fontsize=8)
    ax.set_ylabel("learned − demonstrated (m)")
    ax.grid(True, axis="y", lw=0.3, alpha=0.6, zorder=0)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title or "style kept: run minus demonstration (paper Fig. 11, left)", loc="left")
    for lab in ax.get_xticklabels():
        lab.set_rotation(30)
        lab.set_horizontalalignment("right")


def side_profile(
    ax: Axes, t_s: np.ndarray, left_m: np.ndarray, right_m: np.ndarray, *, title: str | None = None
) -> None:
    """Distance to the left and right walls over one run (paper Fig. 11, right)."""
    ax.plot(t_s, left_m, color=LEFT_COLOR, lw=1.2, label="left (+90°)")
    ax.plot(t_s, right_m, color=RIGHT_COLOR, lw=1.2, label="right (−90°)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("laser range (m)")
    ax.grid(True, lw=0.3, alpha=0.6)
    ax.legend(loc="upper right", fontsize=8)
    if title:
        ax.set_title(title, loc="left")


@dataclass(frozen=True)
class LabelledPath:
    """A path ``(N, 3)`` with a legend label and colour, and whether it achieved what it should."""

    label: str
    pose: np.ndarray
    color: str
    ok: bool = True


def paths_on_map(ax: Axes, world: World, paths: Sequence[LabelledPath], *, title: str | None = None) -> None:
    """Several runs on one map, each from its start (circle) to its end (square; a cross if failed)."""
    draw_world(ax, world)
    for p in paths:
        ax.plot(p.pose[:, 0], p.pose[:, 1], color=p.color, lw=1.6, alpha=0.9, zorder=3, label=p.label)
        ax.plot(*p.pose[0, :2], "o", ms=7, mfc="white", mec=p.color, mew=1.6, zorder=5)
        ax.plot(*p.pose[-1, :2], "s" if p.ok else "X", ms=7, mfc=p.color, mec="black", zorder=5)
    ax.grid(True, lw=0.3, alpha=0.5)
    handles, _ = ax.get_legend_handles_labels()
    handles += [
        Line2D([], [], ls="", marker="o", mfc="white", mec="black", label="start"),
        Line2D([], [], ls="", marker="s", mfc="grey", mec="black", label="end"),
    ]
    if any(not p.ok for p in paths):
        handles.append(Line2D([], [], ls="", marker="X", mfc="grey", mec="black", label="end, failed"))
    ax.legend(handles=handles, loc="best", fontsize=8, framealpha=0.9)
    if title:
        ax.set_title(title, loc="left")
