"""The person model chosen by the data: the hierarchical prior of a discrete demo's rows
(:mod:`lfdfuse.estimate.hierarchy`) and the command model chosen by cross-validated prediction
(:mod:`lfdfuse.estimate.person`)."""

from __future__ import annotations

import numpy as np
import pytest

from lfdfuse.estimate import pooled_estimate
from lfdfuse.estimate.hierarchy import SPREADS, centre_of, hierarchical_rows
from lfdfuse.estimate.methods import EstimateOptions, RowEstimate
from lfdfuse.estimate.person import CANDIDATES, PersonChoice
from lfdfuse.estimate.pipeline import estimate_run
from lfdfuse.estimate.segments import estimate_segments, run_rng
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.read import SegmentedRun


def _flat(n: int) -> RowEstimate:
    return RowEstimate(np.full(n, 1.0 / n), np.full(n, 0.3), None, False)


def _peaked(at: np.ndarray, sharp: float):  # noqa: ANN202
    """A row's log-likelihood peaked at weights ``at`` (the evidence of a few decisions there)."""
    return lambda w: -sharp * ((w - at) ** 2).sum(axis=1)


def test_the_centre_is_the_steps_weights_over_the_rows_behaviours() -> None:
    m = centre_of(np.array([0.6, 0.0, 0.3, 0.1]), [0, 2])
    np.testing.assert_allclose(m, [2 / 3, 1 / 3])
    np.testing.assert_allclose(centre_of(np.array([0.0, 0.0, 1.0]), [0, 1]), [0.5, 0.5])


def test_rows_that_agree_with_their_step_learn_a_strong_prior_and_a_row_without_data_follows_it() -> None:
    centre = np.array([0.8, 0.2])
    rows = [_flat(2) for _ in range(6)] + [_flat(2)]
    logliks = [_peaked(centre, 60.0) for _ in range(6)] + [lambda w: np.zeros(len(w))]
    out, h = hierarchical_rows(rows, [centre] * 7, logliks, 0.5, np.random.default_rng(0))
    assert h.spread >= 4.0, h
    assert len(h.log_evidence) == len(SPREADS)
    # the row of no decisions: the flat prior's mean (0.5) before, near its step's 0.8 after
    assert out[-1].weights[0] > 0.7, out[-1].weights


def test_rows_that_contradict_their_step_keep_the_flat_prior() -> None:
    centre = np.array([0.9, 0.1])
    rows = [_flat(2) for _ in range(6)]
    logliks = [_peaked(np.array([0.1, 0.9]), 200.0) for _ in range(6)]
    out, h = hierarchical_rows(rows, [centre] * 6, logliks, 0.5, np.random.default_rng(0))
    assert h.spread == 0.0, h
    assert all(o is r for o, r in zip(out, rows, strict=True))


def test_a_pinned_row_keeps_its_estimate() -> None:
    pinned = RowEstimate(np.array([0.1, 0.9]), np.full(2, 0.01), None, True)
    out, _ = hierarchical_rows(
        [pinned, _flat(2)],
        [np.array([0.9, 0.1])] * 2,
        [_peaked(np.array([0.1, 0.9]), 500.0), _peaked(np.array([0.9, 0.1]), 30.0)],
        0.5,
        np.random.default_rng(0),
    )
    assert out[0] is pinned


def _varying_run(n: int, truth: float, recorded: str) -> SegmentedRun:
    """A 10 Hz demo whose two behaviours turn with the scan and whose commands are the fused
    heading of weights ``(truth, 1 − truth)`` exactly: a continuous teacher, recorded as ``recorded``."""
    t = np.arange(n)
    a = 0.9 + 0.6 * np.sin(t / 7.0)
    b = -0.9 + 0.6 * np.cos(t / 5.0)
    vec = np.stack([np.stack([np.cos(a), np.sin(a)], -1), np.stack([np.cos(b), np.sin(b)], -1)], 1)
    fused = truth * vec[:, 0] + (1.0 - truth) * vec[:, 1]
    return SegmentedRun(
        names=("wander_left", "wander_right"),
        t_ns=t.astype(np.int64) * 100_000_000,
        vectors=vec,
        applicable=np.ones((n, 2), dtype=bool),
        goal_met=np.zeros((n, 2), dtype=bool),
        demo=fused / np.hypot(fused[:, :1], fused[:, 1:]),
        informative=np.ones(n, dtype=bool),
        bac=np.full(n, 3, dtype=np.int64),
        segment_of=np.zeros(n, dtype=np.int64),
        segments=(GoalSegment(0, 0, n, None),),
        metadata={"segment_commands": recorded},
    )


def test_the_demo_chooses_its_command_model_by_predicting_its_own_decisions(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    run = _varying_run(240, 0.7, "auto")
    opts = EstimateOptions(select_model=True)
    est = estimate_segments(run, opts=opts, rng=run_rng(run, opts))
    assert est.person is not None
    errors = dict(est.person.errors_deg)
    assert len(errors) == len(CANDIDATES)
    # commands on the drive mapping: every candidate fits them, the chosen one to within a few degrees
    assert min(errors.values()) < 3.0, errors
    assert errors[
        est.person.mode if est.person.mode == "continuous" else f"discrete lapse {est.person.lapse:g}"
    ] == min(errors.values())
    w = est.steps[0].fusion[0].weights
    assert abs(w["wander_left"] - 0.7) < 0.05, w
    # the table asks the same chooser of the same demo (cross-validation is the dear part of an
    # estimate: made once here, above); it records the choice and learns with it
    asked: list[SegmentedRun] = []

    def chosen(demo: SegmentedRun, *_: object) -> PersonChoice | None:
        asked.append(demo)
        return est.person

    monkeypatch.setattr(pooled_estimate, "choose_person_model", chosen)
    table, _, _ = estimate_run(run, opts=opts)
    assert len(asked) == 1 and asked[0] is run
    assert table.estimated_by["person_model"] == est.person.provenance()
    assert table.estimated_by["person_model"]["chosen"].startswith(est.person.mode)
    # without the option the detected model, and no choice recorded
    plain, _, _ = estimate_run(run, opts=EstimateOptions())
    assert "person_model" not in plain.estimated_by


def test_a_demo_of_few_decisions_keeps_its_detected_model() -> None:
    run = _varying_run(10, 0.7, "auto")
    opts = EstimateOptions(select_model=True)
    assert estimate_segments(run, opts=opts, rng=run_rng(run, opts)).person is None
