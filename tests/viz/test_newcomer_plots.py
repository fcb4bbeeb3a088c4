"""Plots as a newcomer reads them: the legend whole in the saved file, one
colour per step, a target's name clear of its goal star, one abbreviation table for plots and
the terminal, and an imported log drawn over the walls its own scans saw."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.image import imread
from matplotlib.transforms import Bbox
from typer.testing import CliRunner

from lfdfuse.behaviors.names import ABBREVIATIONS, abbreviation
from lfdfuse.behaviors.primitives import PRESETS
from lfdfuse.cli.main import app
from lfdfuse.cli.render import bac_names
from lfdfuse.evaluate.plot_data import GoalMark, PathData, load_log, scan_points
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.viz import colors
from lfdfuse.viz.plot import map_figure, save_figure, table_figure
from lfdfuse.world.model import load_world
from tests.conftest import ROOT, SHARED

runner = CliRunner()


def _run_data(world: str, steps: int, goals: int) -> PathData:
    """A run along the middle of ``world`` through ``steps`` network steps with long nested names
    (sub-goals), ``goals`` goals reached next to the world's targets, and two collisions."""
    w = load_world(world)
    x0, y0, x1, y1 = w.bounds()
    n = 400
    t = np.linspace(0.0, 1.0, n)
    pose = np.column_stack([x0 + 1 + (x1 - x0 - 2) * t, np.full(n, (y0 + y1) / 2), np.zeros(n)])
    part = np.minimum((t * steps).astype(np.int64), steps - 1)
    names = tuple(f"reach-target-{i}/to-left-opening-{i}" for i in range(steps))
    # the robot stops short of a target on any side: up and right (where a name at a fixed offset would sit), right, above
    sides = [math.radians(a) for a in (45.0, 0.0, 90.0)]
    marks = tuple(
        GoalMark(tg.name, tg.x + 0.6 * math.cos(a), tg.y + 0.6 * math.sin(a), float(i))
        for i, (tg, a) in enumerate(zip(w.targets[:goals], sides, strict=False))
    )
    return PathData("run", "x", w, t * 100, pose, part, names, np.arange(n) % 3, marks, np.array([5, 50]))


def _inside(inner: Bbox, outer: Bbox, tol: float = 1.0) -> bool:
    return (
        inner.x0 >= outer.x0 - tol
        and inner.y0 >= outer.y0 - tol
        and inner.x1 <= outer.x1 + tol
        and inner.y1 <= outer.y1 + tol
    )


def _drawn(fig: Figure, path: Path) -> tuple[Bbox, Bbox]:
    """Save, then the legend's box and the figure's, in the pixels of the saved file."""
    save_figure(fig, path)
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    return fig.legends[0].get_window_extent(renderer), fig.bbox


@pytest.mark.parametrize("world", ["corridor", "building", "office-room"])
@pytest.mark.parametrize(("steps", "goals"), [(3, 1), (9, 3), (16, 3)])
def test_a_run_s_legend_is_whole_in_the_saved_figure(
    world: str, steps: int, goals: int, tmp_path: Path
) -> None:
    fig = map_figure(_run_data(world, steps, goals))
    out = tmp_path / "run.png"
    legend, page = _drawn(fig, out)
    assert _inside(legend, page), (legend, page)
    # nothing of the figure lies beyond the saved page either (a tight box inside the page)
    assert _inside(fig.get_tightbbox().transformed(fig.dpi_scale_trans), page, tol=2.0)
    h, w = imread(out).shape[:2]
    assert abs(w - page.width) <= 1 and abs(h - page.height) <= 1  # the page is the saved image


def test_a_table_s_legend_is_whole_in_the_saved_figure(tmp_path: Path) -> None:
    from lfdfuse.evaluate.roundtrip import load_truth

    truth, _world = load_truth("tee-left")
    legend, page = _drawn(table_figure(truth), tmp_path / "t.png")
    assert _inside(legend, page)


def test_every_step_has_its_own_colour() -> None:
    many = [colors.step_color(i) for i in range(500)]
    assert len({c.lower() for c in many}) == 500
    assert colors.UNKNOWN_COLOR.lower() not in {c.lower() for c in many}  # after the last goal: grey


def test_steps_of_a_run_are_drawn_in_distinct_colours(tmp_path: Path) -> None:
    fig = map_figure(_run_data("building", 12, 0))
    lines = [ln for ln in fig.axes[0].get_lines() if str(ln.get_label()).startswith("network step")]
    assert len(lines) == 12
    assert len({str(ln.get_color()).lower() for ln in lines}) == 12


def test_a_target_s_name_stays_clear_of_its_goal_star(tmp_path: Path) -> None:
    data = _run_data("building", 3, 3)
    fig = map_figure(data)
    save_figure(fig, tmp_path / "g.png")
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    ax = fig.axes[0]
    stars = {
        str(ln.get_label()).split()[1]: ln
        for ln in ax.get_lines()
        if str(ln.get_label()).startswith("reached ")
    }
    names = {t.get_text(): t for t in ax.texts}
    assert set(stars) == {"red", "green", "blue"} and set(stars) <= set(names)
    for target, star in stars.items():
        label = names[target].get_window_extent(renderer)
        mark = star.get_window_extent(renderer)  # the star marker's extent
        assert not label.overlaps(mark), (target, label, mark)


def test_one_abbreviation_table_for_plots_and_terminal() -> None:
    every = [*PRESETS["full"], "attract_red", "attract_green"]
    for name in every:
        short = abbreviation(name)
        # the plot legend explains the very abbreviation the terminal's tables and BACs print
        assert colors.behavior_label(name) == f"{short} = {name}"
        assert bac_names(1, [name]) == short
    assert abbreviation("avoid") == "LA" and abbreviation("wall_attract_left") == "WFL"  # the paper's
    assert bac_names(0b101, ["avoid", "attract_red", "wander_left"]) == "LA+WL"
    # and nobody keeps a table of their own: only lfdfuse/behaviors/names.py maps names to short ones
    for path in (ROOT / "lfdfuse").rglob("*.py"):
        if path.name == "names.py" and path.parent.name == "behaviors":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Dict) and len(node.keys) >= 4:
                keys = {k.value for k in node.keys if isinstance(k, ast.Constant)}
                values = {
                    v.value for v in node.values if isinstance(v, ast.Constant) and isinstance(v.value, str)
                }
                labels_like = keys >= {"avoid", "wander_left"} and len(values) == len(node.values)
                shorts = {v for v in values if len(v) <= 4}
                assert not (labels_like and len(shorts) >= 3), f"{path}: a behaviour abbreviation table"


def test_the_terminal_prints_the_same_abbreviations(tmp_path: Path) -> None:
    from lfdfuse.evaluate.roundtrip import load_truth
    from lfdfuse.network.table import write_table

    truth, _world = load_truth("tee-left")
    write_table(truth, tmp_path / "t.yaml")
    res = runner.invoke(app, ["inspect", str(tmp_path / "t.yaml")])
    assert res.exit_code == 0, res.output
    for b in truth.behaviors:
        assert f"{abbreviation(b)} = {b}" in res.stdout
    assert set(ABBREVIATIONS.values()).isdisjoint({"av", "aL", "wL", "son"})


def test_scan_points_are_the_returns_in_the_pose_frame() -> None:
    g = ScanGeometry(-math.pi / 2, math.pi / 2, 3, 8.0)  # right, ahead, left
    ranges = np.array([[1.0, 8.0, 2.0], [np.inf, 3.0, 0.0]])  # max range, inf and 0: no return
    pose = np.array([[0.0, 0.0, 0.0], [5.0, 1.0, math.pi / 2]])
    pts = scan_points(ranges, g, pose, mount_xy=(0.1, 0.0))
    np.testing.assert_allclose(pts, [[0.1, -1.0], [0.1, 2.0], [5.0, 4.1]], atol=1e-12)
    assert scan_points(np.zeros((0, 3)), g, np.zeros((0, 3))).shape == (0, 2)


def test_an_imported_real_log_plots_over_its_own_scans(tmp_path: Path) -> None:
    bag = SHARED / "realdata" / "ros2" / "macfirst_floor_take_2.mcap"
    if not bag.exists():
        pytest.skip("shared real data not present (../shared/realdata or $LFDFUSE_SHARED)")
    demo = tmp_path / "tb.mcap"
    res = runner.invoke(app, ["import", str(bag), "-o", str(demo)])
    assert res.exit_code == 0, res.output
    data = load_log(demo)
    assert data.world is None and data.scan_points is not None
    assert len(data.scan_points) > 100_000  # 357 scans × 720 beams, less the no-returns
    # the corridor walls are near the path: most returns within the scanner's 12 m of it
    near = np.min(
        np.hypot(*(data.scan_points[::97, None, :] - data.pose[None, ::10, :2]).transpose(2, 0, 1)), axis=1
    )
    assert np.median(near) < 4.0
    out = tmp_path / "tb.png"
    res = runner.invoke(app, ["plot", str(demo), "-o", str(out)])
    assert res.exit_code == 0, res.output
    fig = map_figure(data)
    assert fig.axes[0].images, "the scans' occupancy image is drawn"
    assert "laser returns" in fig.axes[0].get_title(loc="left")
    img = imread(out)
    dark = (img[:, :, :3].max(axis=2) < 0.75) & (np.ptp(img[:, :, :3], axis=2) < 0.05)  # grey walls
    assert dark.sum() > 5000
