"""Behaviour cloning's features and predictions: what each sector reads, headings averaged on the
circle, the same answer every time, and scikit-learn imported only where and when it is needed."""

from __future__ import annotations

import ast
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.evaluate.cloning import CLIP_M, SECTORS, clone_headings, sector_features
from lfdfuse.robot.readings import ScanGeometry
from tests.test_architecture import LIB

FULL = ScanGeometry(-math.pi, 2 * math.pi / 360, 360, 5.0)


def test_a_wall_on_the_left_is_read_by_the_left_sector_alone() -> None:
    r = np.full((1, 360), np.inf)
    left = np.abs(FULL.angles - math.radians(105)) < math.radians(10)  # inside the sector 90°–120°
    r[0, left] = 1.0
    f = sector_features(r, FULL)
    assert f.shape == (1, SECTORS)
    sector = int((math.radians(105) + math.pi) / (2 * math.pi) * SECTORS)
    assert f[0, sector] == 1.0
    assert np.all(np.delete(f[0], sector) == CLIP_M)


@given(
    st.lists(
        st.sampled_from([0.0, -1.0, 0.3, 2.0, 4.5, 5.0, 7.0, math.inf, math.nan]), min_size=181, max_size=181
    )
)
@settings(max_examples=50, deadline=None)
def test_every_sector_reads_a_return_within_the_clip_or_the_clip(ranges: list[float]) -> None:
    """No return (inf, NaN, 0, negative, at or past max range) reads the clip; a half-circle
    scanner's rear sectors read the clip too."""
    half = ScanGeometry(-math.pi / 2, math.pi / 180, 181, 5.0)
    r = np.array([ranges])
    f = sector_features(r, half)
    assert np.all((f > 0) & (f <= CLIP_M))
    valid = r[0][(r[0] > 0) & (r[0] < 5.0)]
    assert f.min() == (min(valid.min(), CLIP_M) if len(valid) else CLIP_M)


def test_headings_either_side_of_behind_average_to_behind() -> None:
    train = np.array([[1.0], [1.01], [1.02]])
    h = np.radians([179.0, -179.0, 179.5])
    got = clone_headings(train, h, np.array([[1.015]]))
    assert abs(abs(math.degrees(got[0])) - 180.0) < 2.0  # not 0°, which averaging the angles gives


def test_the_same_training_steps_give_the_same_predictions() -> None:
    rng = np.random.default_rng(3)
    x, h, q = rng.uniform(0, 4, (80, SECTORS)), rng.uniform(-1, 1, 80), rng.uniform(0, 4, (30, SECTORS))
    a, b = clone_headings(x, h, q), clone_headings(x.copy(), h.copy(), q.copy())
    assert a.tobytes() == b.tobytes()
    assert clone_headings(x[:0], h[:0], q).tolist() == [0.0] * 30  # nothing to clone: straight ahead


def test_only_cloning_imports_scikit_learn_and_only_when_it_clones() -> None:
    """scikit-learn takes a second to import: `lfdfuse --help` must not pay for it."""
    for path in LIB.rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            if any(n.split(".")[0] == "sklearn" for n in names):
                assert path.name == "cloning.py" and node.col_offset > 0, f"{path} imports {names}"
