"""The method registry: every :class:`Method` has an estimator and provenance; nothing falls through."""

from __future__ import annotations

import numpy as np
import pytest

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.methods import (
    POINT_FITS,
    REGISTRY,
    EstimateOptions,
    Likelihood,
    Method,
    estimate_groups,
    is_point_fit,
    method_of,
    provenance,
)
from lfdfuse.estimate.paper import PFParams
from lfdfuse.estimate.smc import SMCParams
from lfdfuse.evaluate.holdout import METHODS


def test_every_method_is_registered_and_named_by_its_value() -> None:
    assert set(REGISTRY) == set(Method)
    for m in Method:
        assert method_of(m.value) is m and str(m) == m.value
        by = provenance(EstimateOptions(method=m, seed=3), source="d.seg.mcap")
        assert by["method"] == m.value and type(by["method"]) is str  # plain YAML, no enum tag
        assert list(by)[:4] == ["method", "trials", "seed", "source"]
    assert {Likelihood(x).literal for x in ("paper", "vonmises")} == {"paper", "vonmises"}


def test_an_unknown_method_is_a_config_error_not_a_fallback() -> None:
    with pytest.raises(ConfigError, match=r"unknown method 'magic' \(valid: pf, paper, nnls, arbitration\)"):
        method_of("magic")
    opts = EstimateOptions(method="magic")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="unknown method"):
        estimate_groups([(np.zeros((3, 2, 2)), np.zeros((3, 2)))], opts=opts, rng=np.random.default_rng(0))


@pytest.mark.parametrize("method", list(Method))
def test_every_method_recovers_a_noise_free_fusion(method: Method) -> None:
    rng = np.random.default_rng(7)
    truth = np.array([0.7, 0.3])
    vec = rng.normal(0.0, 1.0, (80, 2, 2))
    fused = np.einsum("tkd,k->td", vec, truth)
    demo = fused / np.linalg.norm(fused, axis=1, keepdims=True)
    opts = EstimateOptions(method=method, smc=SMCParams(particles=128), pf=PFParams(particles=300))
    (est,) = estimate_groups([(vec, demo)], opts=opts, rng=np.random.default_rng(1))
    assert est.weights.sum() == pytest.approx(1.0)
    if method is Method.ARBITRATION:
        assert np.array_equal(est.weights, [1.0, 0.0])  # one behaviour wins
    else:
        assert np.abs(est.weights - truth).sum() < 0.1, est.weights


@pytest.mark.parametrize("method", list(Method))
def test_a_point_fit_is_a_method_with_no_spread_of_its_own(method: Method) -> None:
    """``point_fit`` says what the estimate shows: one trial of a point fit has std 0 (render hides
    it, evaluate scores it as a baseline); a posterior method reports a spread."""
    rng = np.random.default_rng(5)
    vec = rng.normal(0.0, 1.0, (60, 3, 2))
    fused = np.einsum("tkd,k->td", vec, [0.5, 0.3, 0.2]) + rng.normal(0.0, 0.3, (60, 2))
    demo = fused / np.linalg.norm(fused, axis=1, keepdims=True)
    opts = EstimateOptions(method=method, smc=SMCParams(particles=128), pf=PFParams(particles=300))
    (est,) = estimate_groups([(vec, demo)], opts=opts, rng=np.random.default_rng(1))
    assert REGISTRY[method].point_fit == (not est.std.any())
    assert is_point_fit(method.value) == REGISTRY[method].point_fit
    assert REGISTRY[method].label


def test_evaluate_scores_every_point_fit_and_names_no_other_method() -> None:
    assert POINT_FITS == (Method.NNLS, Method.ARBITRATION)
    assert METHODS == ("fused", "nnls", "arbitration", "straight", "previous", "oracle")
    assert not is_point_fit("magic") and not is_point_fit(None)
