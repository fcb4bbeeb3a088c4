"""A fused heading read as a person's key press: the heading of the key whose bin holds it (the
model's median), and the key response fitted on training decisions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lfdfuse.estimate.keys import fit_key_response, key_heading, key_of
from lfdfuse.estimate.model import CommandBins, FusionModel

KEYS = CommandBins.from_headings([-math.pi / 2, -0.66, 0.0, 0.66, math.pi / 2])
MODEL = FusionModel()


def _presses(phi: np.ndarray, sigma_deg: float, rng: np.random.Generator) -> np.ndarray:
    """The discrete model's person: the key whose bin holds the noisy fused heading."""
    noisy = phi + rng.vonmises(0.0, 1.0 / math.radians(sigma_deg) ** 2, len(phi))
    return key_of(KEYS, noisy)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_key_heading_is_the_prediction_of_least_absolute_error(seed: int) -> None:
    """For a person of the discrete model, the heading of the key whose bin holds the fused heading
    errs less (mean absolute) than the fused heading itself and than any other key's heading."""
    rng = np.random.default_rng(seed)
    phi = rng.uniform(-1.2, 1.2, 200)
    h = np.array(KEYS.headings)
    presses = np.stack([_presses(phi, 15.0, rng) for _ in range(200)])  # (draws, N)
    said = h[presses]

    def err(pred: np.ndarray) -> float:
        return float(np.abs(said - pred[None, :]).mean())

    read = key_heading(KEYS, phi)
    assert err(read) < err(phi) - 0.02
    for shift in (-1, 1):  # a neighbouring key instead
        other = h[np.clip(key_of(KEYS, phi) + shift, 0, KEYS.size - 1)]
        assert err(read) < err(other)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_key_response_finds_the_noise_and_predicts_the_bin_when_the_fusion_tells(seed: int) -> None:
    rng = np.random.default_rng(seed)
    phi = rng.uniform(-1.5, 1.5, 300)
    sharp = fit_key_response(KEYS, phi, _presses(phi, 5.0, rng), MODEL)
    broad = fit_key_response(KEYS, phi, _presses(phi, 40.0, rng), MODEL)
    assert sharp.sigma_deg < 12.0 < 25.0 < broad.sigma_deg, (sharp.sigma_deg, broad.sigma_deg)
    test = rng.uniform(-1.5, 1.5, 300)
    truth = _presses(test, 5.0, rng)
    acc = float((sharp.key(test, MODEL) == truth).mean())
    assert acc > 0.85 and acc >= float((key_of(KEYS, test) == truth).mean()) - 0.02


def test_where_the_fusion_says_nothing_the_key_pressed_most_wins() -> None:
    """A person who holds 'forward' three times in four whatever the fused heading: the response
    learns that the fused heading says little, and predicts forward — as often right as the most
    common key, where the bin of the fused heading is right one time in five."""
    rng = np.random.default_rng(3)
    n = 400
    phi = rng.uniform(-1.5, 1.5, n)
    keys = np.where(rng.random(n) < 0.75, 2, rng.integers(0, KEYS.size, n))
    r = fit_key_response(KEYS, phi[: n // 2], keys[: n // 2], MODEL)
    test, truth = phi[n // 2 :], keys[n // 2 :]
    got = float((r.key(test, MODEL) == truth).mean())
    most = float((truth == 2).mean())
    assert got >= most - 0.01 and got > float((key_of(KEYS, test) == truth).mean()) + 0.3
    assert r.frequencies[2] > 0.6 and r.sigma_deg > 30.0
    prov = r.provenance()
    assert set(prov) == {"sigma_deg", "key_shares"} and len(prov["key_shares"]) == KEYS.size  # type: ignore[arg-type]


def test_stops_and_reverses_are_no_key_and_no_decision_is_the_broadest_response() -> None:
    phi = np.array([0.0, 0.1, 1.4])
    r = fit_key_response(KEYS, phi, np.array([-1, 2, -1]), MODEL)
    assert r.frequencies[2] == max(r.frequencies) and math.isclose(sum(r.frequencies), 1.0)
    empty = fit_key_response(KEYS, phi, np.array([-1, -1, -1]), MODEL)
    assert empty.sigma_deg == pytest.approx(MODEL.sigma_max_deg)
    assert np.allclose(empty.frequencies, 1.0 / KEYS.size)
    assert empty.key(np.zeros(0), MODEL).shape == (0,)
