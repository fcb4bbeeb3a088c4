from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.offroute import CASES, demonstrate


@pytest.fixture(scope="session")
def ring_spur_demo(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The ring-spur task's teacher demo (seed 1), segmented, for every test that learns from it
    (each reads it and writes nothing beside it)."""
    return demonstrate(CASES["ring-spur"], folder=tmp_path_factory.mktemp("ring-spur"))
