"""The hostile corpus against the CLI. ``make test`` runs a sample of every class;
``make fuzz`` (``LFDFUSE_FUZZ=1``) runs all of it."""

from __future__ import annotations

import os
from collections import Counter
from pathlib import Path

import pytest

from tests.hostile.base import Base, build_base
from tests.hostile.cases import CLASSES, corpus, sample
from tests.hostile.runner import Case, check

FULL = os.environ.get("LFDFUSE_FUZZ") == "1"
CASES = corpus() if FULL else sample()


@pytest.fixture(scope="session")
def base(tmp_path_factory: pytest.TempPathFactory) -> Base:
    return build_base(tmp_path_factory.mktemp("hostile-base"))


@pytest.mark.parametrize("case", CASES, ids=[f"{c.cls}:{c.id}" for c in CASES])
def test_hostile(case: Case, base: Base, tmp_path: Path) -> None:
    check(case, tmp_path, base)


def test_the_corpus_is_large_and_the_sample_covers_every_class() -> None:
    full = corpus()
    assert len(full) >= 200
    assert len({c.id for c in full if c.cls == "paths"}) == len([c for c in full if c.cls == "paths"])
    assert set(Counter(c.cls for c in sample())) == set(CLASSES)
