"""``lfdfuse plot``: a log or a fusion table into one figure, written atomically as PNG or SVG.

Figures are built on :class:`matplotlib.figure.Figure` directly (no pyplot, no global state,
no GUI backend); PNG goes through Agg, SVG through matplotlib's SVG writer, both with fixed
metadata so the same input gives the same bytes.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib
from matplotlib.figure import Figure
from matplotlib.legend import Legend

from lfdfuse.errors import ConfigError, LfdError
from lfdfuse.evaluate.plot_data import PERSON_PART, PathData, load_log
from lfdfuse.files import write_bytes_atomic
from lfdfuse.network.table import FusionTable, load_table, table_steps
from lfdfuse.viz import figures
from lfdfuse.words import counted

FORMATS = ("png", "svg")
DPI = 100


@dataclass(frozen=True)
class PlotResult:
    out: str
    kind: str  # demo, segmented, run or table
    width_px: int
    height_px: int
    summary: str


def figure_format(path: str | Path) -> str:
    fmt = Path(path).suffix.lower().lstrip(".")
    if fmt not in FORMATS:
        raise ConfigError(f"cannot write {path}: the output must end in .png or .svg")
    return fmt


def save_figure(fig: Figure, path: str | Path) -> tuple[int, int]:
    """Render ``fig`` as PNG or SVG (by suffix) and write it atomically; returns its size in pixels."""
    fmt = figure_format(path)
    buf = io.BytesIO()
    meta = {"Date": None} if fmt == "svg" else {"Software": None}
    with matplotlib.rc_context({"svg.hashsalt": "lfdfuse", "svg.fonttype": "path"}):
        fig.savefig(buf, format=fmt, dpi=DPI, metadata=meta)
    w, h = fig.get_size_inches() * DPI
    write_bytes_atomic(Path(path), buf.getvalue())
    return round(w), round(h)


def map_figure(data: PathData, *, title: str | None = None) -> Figure:
    """A log on its map, sized to the map's shape (at least 1000 × 625 px), legend below."""
    if data.world is not None:
        x0, y0, x1, y1 = data.world.bounds()
        aspect = (y1 - y0 + 1.0) / max(x1 - x0 + 1.0, 1e-9)
    elif data.scan_points is not None and len(data.scan_points):
        lo, hi = figures.scan_extent(data.scan_points, data.pose[:, :2])
        aspect = float(hi[1] - lo[1]) / max(float(hi[0] - lo[0]), 1e-9)
    else:
        aspect = 0.6
    width = 10.0
    height = min(max(width * aspect + 1.8, 6.25), 11.0)
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    ax = fig.add_subplot()
    figures.log_map(ax, data, title=title)
    handles, labels = ax.get_legend_handles_labels()
    legend_below(fig, handles, labels)
    return fig


#: the room (inches) a figure keeps below its axes for a legend of about two rows
LEGEND_ROOM_IN = 0.6


def legend_below(fig: Figure, handles: list[Any], labels: list[str], *, max_cols: int = 4) -> Legend:
    """The figure's legend below its axes, in as many columns (at most ``max_cols``) as fit its
    width — long step names in four columns ran off both sides — and the figure grown by the
    rows past :data:`LEGEND_ROOM_IN`, so the legend is whole in the saved file and the map keeps
    its size."""
    cols = max(1, min(max_cols, len(handles)))
    while True:
        legend = fig.legend(
            handles, labels, loc="outside lower center", ncols=cols, fontsize=8, frameon=False
        )
        box = legend.get_window_extent()
        if box.width <= 0.98 * fig.bbox.width or cols == 1:
            break
        legend.remove()
        cols -= 1
    extra = box.height / fig.dpi - LEGEND_ROOM_IN
    if extra > 0:
        w, h = fig.get_size_inches()
        fig.set_size_inches(w, h + extra)
    return legend


def table_figure(table: FusionTable, *, spread: str = "std", title: str | None = None) -> Figure:
    """Each fusion primitive of a table as a row of weight bars, one legend of behaviours."""
    steps = table_steps(table)
    if not steps:
        raise ConfigError("the fusion table has no fusion primitive to draw")
    widest = max(len(s.rows) for s in steps)
    fig = Figure(
        figsize=(max(10.0, 0.9 * widest + 2.0), max(6.25, 2.9 * len(steps) + 1.2)),
        dpi=DPI,
        layout="constrained",
    )
    axes = fig.subplots(len(steps), 1, squeeze=False)[:, 0]
    drawn: list[str] = []
    for ax, step in zip(axes, steps, strict=True):
        for n in figures.weight_bars(ax, step, table.behaviors, spread=spread):
            if n not in drawn:
                drawn.append(n)
    order = [b for b in table.behaviors if b in drawn]
    handles = figures.behavior_legend_handles(order)
    legend_below(fig, list(handles), [str(h.get_label()) for h in handles])
    name = table.network.name
    fig.suptitle(title or f"fusion table {name}: weights per BAC row", x=0.01, ha="left")
    return fig


def plot_file(
    src: str | Path, out: str | Path, *, title: str | None = None, spread: str = "std"
) -> PlotResult:
    """Draw a demo, segmented or run MCAP (a map) or a fusion table YAML (weight bars) into ``out``.

    ``spread``: the whiskers of weight bars, ``std`` (posterior) or ``trial_std`` (over trials).
    """
    if spread not in ("std", "trial_std"):
        raise ConfigError(f"unknown whiskers {spread!r} (valid: std, trial_std)")
    figure_format(out)
    p = Path(src)
    if p.is_dir():
        raise LfdError(f"{p} is a folder: plot draws one MCAP log or one fusion table")
    if not p.is_file():
        raise LfdError(f"no such file: {p}")
    if Path(out).resolve() == p.resolve():
        raise LfdError("the output must not overwrite the input")
    if p.suffix.lower() in (".yaml", ".yml"):
        table = load_table(p)
        if spread == "trial_std" and not _has_trial_std(table):
            raise ConfigError(f"{p} has no trial_std: estimate with --trials K (K > 1) first")
        w, h = save_figure(table_figure(table, spread=spread, title=title), out)
        steps = table_steps(table)
        rows = sum(len(s.rows) for s in steps)
        return PlotResult(str(out), "table", w, h, f"{len(steps)} steps, {rows} BAC rows")
    data = load_log(p)
    w, h = save_figure(map_figure(data, title=title), out)
    step_names = [n for n in data.part_names if n != PERSON_PART]
    parts = "" if data.kind == "demo" else f", {counted(len(step_names), data.part_label)}"
    if PERSON_PART in data.part_names:
        mine = int((data.part == data.part_names.index(PERSON_PART)).sum())
        parts += f" (the person drove {counted(mine, 'scan')})"
    summary = (
        f"{data.kind}: {len(data.t_s)} scans{parts}, {len(data.bac_changes())} BAC changes, "
        f"{counted(len(data.goals), 'goal reached', 'goals reached')}, {counted(len(data.collisions), 'collision')}"
    )
    return PlotResult(str(out), data.kind, w, h, summary)


def _has_trial_std(table: FusionTable) -> bool:
    return any(r.trial_std is not None for s in table_steps(table) for r in s.rows)
