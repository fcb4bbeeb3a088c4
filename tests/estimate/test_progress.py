"""Long estimates report real progress while they work.

A callback fired only at the end would show ``0%`` for the whole of ``estimate --trials 30``.
Every method tells its ``progress`` as it goes — the tempered SMC every iteration, the paper's
filter every few updates, the baselines per row — and the fraction only grows.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.estimate.methods import EstimateOptions, Method, estimate_groups
from lfdfuse.estimate.paper import PFParams
from lfdfuse.estimate.smc import SMCParams, TemperedSMC
from lfdfuse.learn import LearnOptions, demonstrate, learn
from lfdfuse.progress import part
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world


def _problems(
    rng: np.random.Generator, sizes: tuple[int, ...] = (40, 25, 60, 12)
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Rows of unit behaviour vectors steered by a known fusion, with a little heading noise."""
    out = []
    for t in sizes:
        a = rng.uniform(-1.5, 1.5, (t, 3))
        vec = np.stack([np.cos(a), np.sin(a)], axis=-1)  # (T, 3, 2)
        f = (vec * np.array([0.5, 0.3, 0.2])[None, :, None]).sum(axis=1)
        h = np.arctan2(f[:, 1], f[:, 0]) + rng.normal(0.0, 0.05, t)
        out.append((vec, np.stack([np.cos(h), np.sin(h)], axis=1)))
    return out


def _fractions(calls: list[tuple[float, float]]) -> np.ndarray:
    assert all(total > 0 for _, total in calls), calls
    return np.array([done / total for done, total in calls])


@pytest.mark.parametrize(
    ("method", "least"),
    [(Method.PF, 10), (Method.PAPER, 10), (Method.NNLS, 4), (Method.ARBITRATION, 4)],
)
def test_every_method_reports_growing_progress_while_it_works(method: Method, least: int) -> None:
    calls: list[tuple[float, float]] = []
    opts = EstimateOptions(
        method=method,
        trials=3,
        smc=replace(SMCParams(), particles=64),
        pf=replace(PFParams(), particles=64, min_updates=100),
    )
    rows = estimate_groups(
        _problems(np.random.default_rng(0)),
        opts=opts,
        rng=np.random.default_rng(1),
        progress=lambda d, t: calls.append((d, t)),
    )
    assert len(rows) == 4
    f = _fractions(calls)
    assert len(f) >= least, f  # many reports, not one at the end
    assert np.all(np.diff(f) >= -1e-12), f  # never goes back
    assert f[0] <= 0.05 and f[-1] == pytest.approx(1.0)
    # reports in between: the work is visible while it happens
    assert ((f > 0.05) & (f < 0.95)).sum() >= least // 2, f


def test_the_sampler_s_own_progress_grows_from_zero_to_one() -> None:
    """:attr:`TemperedSMC.progress` after every iteration: 0 before, 1 when done, never back."""
    from lfdfuse.estimate.model import FusionModel, make_row

    rows = [make_row(v, d, None) for v, d in _problems(np.random.default_rng(2))]
    smc = TemperedSMC(
        rows, trials=2, model=FusionModel(), params=SMCParams(particles=64), rng=np.random.default_rng(3)
    )
    seen = [smc.progress]
    for _ in smc:
        seen.append(smc.progress)
    assert seen[0] == 0.0 and seen[-1] == 1.0 and smc.done
    assert np.all(np.diff(seen) >= 0.0), seen
    assert len(seen) >= 5 and len(set(np.round(seen, 3))) >= 5, seen  # it moves, not jumps at the end


def test_part_maps_a_sub_task_into_its_slice() -> None:
    got: list[float] = []
    sub = part(lambda d, t: got.append(d / t), start=1.0, size=2.0, total=4.0)
    assert sub is not None
    for d in (0.0, 5.0, 10.0, 20.0):  # past its own total: clamped to its slice
        sub(d, 10.0)
    assert got == [0.25, 0.5, 0.75, 0.75]
    assert part(None, start=0.0, size=1.0, total=1.0) is None


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("progress")
    d = demonstrate(
        (Leg(None, "keep-left"),), world=load_world("tee"), folder=folder, name="d", duration_s=12.0, seed=4
    )
    return d.segmented


def test_learning_a_demo_reports_progress_many_times(demo: Path) -> None:
    calls: list[tuple[float, float]] = []
    opts = EstimateOptions(trials=4, smc=replace(SMCParams(), particles=64))
    plain = learn([demo], options=LearnOptions(estimate=opts))
    told = learn([demo], options=LearnOptions(estimate=opts), progress=lambda d, t: calls.append((d, t)))
    assert told.table == plain.table  # telling progress changes nothing learned
    f = _fractions(calls)
    assert len(f) >= 10 and np.all(np.diff(f) >= -1e-12) and f[-1] == pytest.approx(1.0), f
    assert ((f > 0.05) & (f < 0.95)).sum() >= 5, f


def test_estimate_prints_cleanly_when_piped(demo: Path, tmp_path: Path) -> None:
    """Piped (not a terminal) the bar is not drawn: stdout is the summary, stderr is empty."""
    out = tmp_path / "f.yaml"
    res = CliRunner().invoke(
        app, ["estimate", str(demo), "--trials", "3", "--particles", "64", "-o", str(out)]
    )
    assert res.exit_code == 0, res.output
    assert res.stderr == ""
    for junk in ("\r", "\x1b[", "-:--:--", "━"):
        assert junk not in res.stdout, repr(junk)
    assert res.stdout.startswith(f"estimate {demo} → {out}")


def test_pooled_learning_reports_progress_that_only_grows(demo: Path, tmp_path: Path) -> None:
    """Two demos: the first one's pass, then the rows the second adds steps to, in one range."""
    twin = tmp_path / "twin.seg.mcap"
    twin.write_bytes(demo.read_bytes())
    calls: list[tuple[float, float]] = []
    opts = EstimateOptions(trials=2, smc=replace(SMCParams(), particles=64))
    learn([demo, twin], options=LearnOptions(estimate=opts), progress=lambda d, t: calls.append((d, t)))
    f = _fractions(calls)
    assert len(f) >= 10 and np.all(np.diff(f) >= -1e-12) and f[-1] == pytest.approx(1.0), f
    assert ((f > 0.5) & (f < 0.99)).sum() >= 3, f  # the pooled rows report too, not only the first pass
