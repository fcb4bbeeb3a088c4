"""What ``segment_file`` measures beside the log: the step time and the best command lag."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lfdfuse.segment.lag import CANDIDATE_LAGS_S, LagFit
from lfdfuse.segment.pipeline import SegmentResult, segment_file, step_s_of
from lfdfuse.sim.robot import RobotParams
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("lag") / "d.mcap"
    opts = SimulateOptions(
        world=load_world("corridor"),
        legs=[Leg(None, "keep-right")],
        teacher_name="t",
        duration_s=20.0,
        seed=4,
    )
    simulate(opts, out=out)
    return out


@pytest.mark.parametrize("lag_s", [0.0, 0.3, 0.25])
def test_the_best_lag_is_the_smallest_error_of_the_measured_ones(
    demo: Path, tmp_path: Path, lag_s: float
) -> None:
    res = segment_file(demo, out=tmp_path / "s.mcap", lag_s=lag_s)
    measured = [f for f in res.lag_fits if f.steps > 0]
    assert [f.lag_s for f in res.lag_fits] == list(CANDIDATE_LAGS_S)
    best = res.best_lag
    assert best is not None and best in measured
    assert all(best.heading_error_deg <= f.heading_error_deg for f in measured)
    here = res.fit_at_lag
    if lag_s in CANDIDATE_LAGS_S:
        assert here is not None and here.lag_s == lag_s
        assert best.heading_error_deg <= here.heading_error_deg
    else:
        assert here is None  # 0.25 s is between two candidates: no fit was made at it


def test_nothing_measured_is_no_best_lag(demo: Path, tmp_path: Path) -> None:
    res = segment_file(demo, out=tmp_path / "s.mcap", measure_lag=False)
    assert res.lag_fits == () and res.best_lag is None and res.fit_at_lag is None
    assert res.step_s == pytest.approx(RobotParams().dt_s)


def _result(fits: tuple[LagFit, ...], lag_s: float = 0.0) -> SegmentResult:
    return SegmentResult((), None, np.zeros(0, np.int64), np.zeros(0, bool), "x", lag_s, fits)  # type: ignore[arg-type]


def test_ties_go_to_the_shorter_lag_and_empty_fits_never_win() -> None:
    fits = (LagFit(0.0, 5.0, 0), LagFit(0.1, 3.0, 10), LagFit(0.2, 3.0, 10), LagFit(0.3, 4.0, 10))
    res = _result(fits, lag_s=0.0)
    assert res.best_lag == fits[1]
    assert res.fit_at_lag is None  # the fit at 0.0 had no informative steps


def test_step_time_is_the_median_gap() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        dt = int(rng.integers(10_000_000, 500_000_000))
        t = np.cumsum(np.full(50, dt))
        t[::7] += int(rng.integers(0, dt // 3))  # a few late stamps do not move the median
        assert step_s_of(t) == dt / 1e9  # 16 of 49 gaps moved: the median is still dt
    assert step_s_of(np.array([5], np.int64)) == RobotParams().dt_s
