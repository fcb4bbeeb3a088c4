"""The frozen dataclasses a live tick makes without their ``__init__``: the same instances."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from lfdfuse.behaviors.primitives import BehaviorOutputs, made_outputs
from lfdfuse.behaviors.spec import Observations, made_observations
from lfdfuse.network.runtime import Decision, made_decision
from lfdfuse.robot.readings import ScanGeometry


def _same(made: object, built: object) -> None:
    """Equal, with every field and nothing else, the same repr, and still frozen; the class
    checks nothing in ``__post_init__`` (which making it without ``__init__`` would skip)."""
    assert type(made) is type(built)
    assert not hasattr(type(built), "__post_init__")
    assert made == built and repr(made) == repr(built)
    names = [f.name for f in dataclasses.fields(built)]  # type: ignore[arg-type]
    assert list(vars(made)) == names
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(made, names[0], None)


def test_a_made_decision_is_the_decision() -> None:
    fused = np.array([0.5, -0.25])
    fields = (None, (0, 2), 0b1011, {"avoid": 0.3}, True, fused, ("red",))
    _same(made_decision(*fields), Decision(*fields))


def test_made_observations_are_the_observations() -> None:
    g = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 30.0)
    nan = np.full((1, 2), np.nan)
    fields = (np.ones((1, 181)), g, None, None, 5.0, ("red", "blue"), nan, nan, np.zeros((1, 3)))
    _same(made_observations(*fields), Observations(*fields))


def test_made_outputs_are_the_outputs() -> None:
    fields = (("avoid", "wander"), np.zeros((1, 2, 2)), np.ones((1, 2), bool), np.zeros((1, 2), bool))
    _same(made_outputs(*fields), BehaviorOutputs(*fields))
