"""``lfdfuse plot``: the real command on a demo, a segmented demo, a run and a table; pixels and SVG checked."""

from __future__ import annotations

import json
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from matplotlib.colors import to_rgb
from matplotlib.image import imread
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.evaluate.plot_data import load_log
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.learn import LearnOptions, demonstrate, learn
from lfdfuse.log import lfd
from lfdfuse.log.messages import TOPICS
from lfdfuse.network.table import write_table
from lfdfuse.sources.tasks import Leg
from lfdfuse.viz import colors
from lfdfuse.viz.plot import map_figure, save_figure
from lfdfuse.world.model import load_world
from tests.conftest import ROOT

runner = CliRunner()


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A short three-goal demo in building (goals reached), its segmented log, table and a run."""
    tmp = tmp_path_factory.mktemp("plot")
    table, run = tmp / "t.yaml", tmp / "r.mcap"
    legs = [Leg("red", "keep-left"), Leg("green", "keep-center")]
    d = demonstrate(
        legs, world=load_world("building"), folder=tmp, name="d", duration_s=120, seed=1, measure_lag=False
    )
    demo, seg = d.raw, d.segmented
    tab = learn([seg], options=LearnOptions(EstimateOptions(seed=1, trials=2))).table
    write_table(tab, table)
    run_table(
        ExecuteOptions(world=load_world("building"), table=tab, max_time_s=90), out=run, command="execute"
    )
    return {"demo": demo, "seg": seg, "table": table, "run": run}


def plot(src: Path, out: Path, *extra: str) -> str:
    res = runner.invoke(app, ["plot", str(src), "-o", str(out), *extra])
    assert res.exit_code == 0, res.output
    return res.output


def pixels_near(img: np.ndarray, color: str, tol: float = 0.06) -> int:
    """How many pixels are within ``tol`` of a colour (RGB in [0, 1])."""
    rgb = np.array(to_rgb(color))
    return int((np.abs(img[:, :, :3] - rgb).max(axis=2) < tol).sum())


def test_demo_png_has_map_path_and_size(files: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "demo.png"
    text = plot(files["demo"], out)
    assert "demo:" in text and "1000×" in text
    img = imread(out)
    assert img.shape[1] >= 800 and img.shape[0] >= 500
    assert pixels_near(img, colors.PATH_COLOR) > 300  # the demonstrated path in red
    assert pixels_near(img, colors.WALL_COLOR, 0.1) > 2000  # the building's walls
    assert pixels_near(img, colors.target_color("green")) > 30  # a target


def test_segmented_png_colours_goal_segments_and_marks_goals(files: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "seg.png"
    text = plot(files["seg"], out)
    assert "segmented:" in text and "2 goals reached" in text
    img = imread(out)
    for j in range(2):  # to red, to green
        assert pixels_near(img, colors.step_color(j)) > 100, j


def test_walls_are_dark_where_the_map_says(files: dict[str, Path], tmp_path: Path) -> None:
    """Pixels at points on the walls (through the axes transform) are dark; mid-corridor is not."""
    data = load_log(files["seg"])
    fig = map_figure(data)
    out = tmp_path / "w.png"
    w, h = save_figure(fig, out)
    img = imread(out)
    assert img.shape[:2] == (h, w)
    ax = fig.axes[0]
    world = data.world
    assert world is not None

    def px(x: float, y: float) -> np.ndarray:
        dx, dy = ax.transData.transform((x, y))
        return img[int(round(h - dy)), int(round(dx)), :3]

    for x, y in [(10.0, 0.0), (0.0, 15.0), (10.0, 2.4), (30.0, 13.8)]:  # outer and inner walls
        assert px(x, y).mean() < 0.35, (x, y, px(x, y))
    assert px(10.0, 20.0).mean() > 0.9  # inside a block: nothing drawn


def test_run_svg_structure(files: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "run.svg"
    text = plot(files["run"], out)
    assert "run:" in text
    root = ET.parse(out).getroot()
    assert root.tag.endswith("svg")
    ids = {el.get("id") for el in root.iter()}
    assert "axes_1" in ids and "legend_1" in ids
    assert sum(1 for i in ids if i and i.startswith("line2d_")) > 10
    body = out.read_text()
    assert colors.step_color(0).lower() in body.lower()  # the first network step's colour
    assert float(root.get("width", "0").rstrip("pt")) >= 600  # points: 1000 px at 100 dpi = 720 pt


def test_table_png_has_behaviour_colours(files: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "t.png"
    text = plot(files["table"], out)
    assert "BAC rows" in text
    img = imread(out)
    assert img.shape[1] >= 800 and img.shape[0] >= 500
    assert pixels_near(img, colors.behavior_color("wander_left")) > 100
    assert pixels_near(img, colors.behavior_color("wall_attract_left")) > 100
    out2 = tmp_path / "t2.svg"
    plot(files["table"], out2, "--whiskers", "trial_std")
    assert ET.parse(out2).getroot().tag.endswith("svg")


def test_same_input_same_bytes(files: dict[str, Path], tmp_path: Path) -> None:
    for suffix in ("png", "svg"):
        a, b = tmp_path / f"a.{suffix}", tmp_path / f"b.{suffix}"
        plot(files["table"], a)
        plot(files["table"], b)
        assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["missing.mcap", "-o", "x.png"], "no such file"),
        (["{table}", "-o", "x.jpg"], ".png or .svg"),
    ],
)
def test_user_errors_are_one_line(
    files: dict[str, Path], tmp_path: Path, args: list[str], needle: str
) -> None:
    args = [a.replace("{table}", str(files["table"])) for a in args]
    res = runner.invoke(app, ["plot", *args])
    assert res.exit_code == 1
    assert res.output.strip().startswith("error:") and needle in res.output
    assert "Traceback" not in res.output


def test_installed_command_and_help_without_matplotlib(files: dict[str, Path], tmp_path: Path) -> None:
    exe = Path(sys.executable).parent / "lfdfuse"
    out = tmp_path / "cli.png"
    res = subprocess.run(
        [str(exe), "plot", str(files["seg"]), "-o", str(out)], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code = "import sys, lfdfuse.cli.main; print('matplotlib' in sys.modules)"
    assert (
        subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip() == "False"
    )


def test_run_layout_names_channels_that_runs_have() -> None:
    layout = json.loads((ROOT / "lfdfuse" / "foxglove" / "run-layout.json").read_text())
    known = set(TOPICS) | set(lfd.EXECUTE_TOPICS)
    topics = set(layout["configById"]["3D!lfdfuse-run"]["topics"])
    paths = [
        p["value"]
        for key, cfg in layout["configById"].items()
        if key.split("!")[0] in ("Plot", "StateTransitions")
        for p in cfg["paths"]
    ]
    used = topics | {p.split(".")[0] for p in paths}
    assert used <= known, used - known
    assert {"/world", "/scan", "/pose", "/lfd/overlay"} <= topics


def test_a_correction_plots_the_persons_ticks_as_the_persons(tmp_path: Path) -> None:
    """Who drove is shown: the ticks a person drove are their own part, not the network's step."""
    from lfdfuse.evaluate.plot_data import PERSON_PART
    from tests.sources.teleop.correction import correction_log

    path, person = correction_log(tmp_path)
    data = load_log(path)
    theirs = np.flatnonzero(data.part == data.part_names.index(PERSON_PART))
    # one takeover: as many ticks as the person drove, in one stretch; the rest the network's
    assert len(theirs) == len(person) and np.all(np.diff(theirs) == 1)
    assert np.all(data.part[data.part != data.part_names.index(PERSON_PART)] >= 0)
    res = CliRunner().invoke(app, ["plot", str(path), "-o", str(tmp_path / "fix.png")])
    assert res.exit_code == 0, res.output
    assert f"1 network step (the person drove {len(person)} scans)" in res.output, res.output
