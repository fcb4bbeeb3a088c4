"""Weights for unseen BACs made safe: ``avoid`` at least at its default, every row as it was.

Laws over random nested tables (:func:`lfdfuse.network.table.safe_defaults`), and what
:func:`lfdfuse.network.changes.step_changes` says of the change.
"""

from __future__ import annotations

import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.behaviors.catalogue import CATALOGUE
from lfdfuse.network.changes import step_changes
from lfdfuse.network.landmark_goals import Landmark
from lfdfuse.network.table import (
    FusionRow,
    FusionTable,
    Network,
    Step,
    dump_table,
    parse_table,
    safe_defaults,
)

NAMES = ("avoid", "sonar_avoid", "attract_red", "wander_left", "wander_right", "wall_attract_left")
#: the fixed behaviours' default weights, from the catalogue (avoid 1, sonar_avoid 0.5)
FLOOR = {s.name: s.default_weight for s in CATALOGUE if not s.family and s.default_role == "fixed"}

weight = st.floats(0.0, 2.0, allow_nan=False).map(lambda x: round(x, 4))


@st.composite
def weights(draw: st.DrawFn, names: tuple[str, ...]) -> dict[str, float]:
    keys = draw(st.lists(st.sampled_from(names), min_size=1, unique=True))
    return {k: draw(weight) for k in keys}


@st.composite
def network(draw: st.DrawFn, name: str, names: tuple[str, ...], depth: int) -> Network:
    n = draw(st.integers(1, 3))
    return Network(name, tuple(draw(steps(f"{name}-{i}", names, depth)) for i in range(n)))


@st.composite
def steps(draw: st.DrawFn, name: str, names: tuple[str, ...], depth: int) -> Step:
    if depth and draw(st.booleans()):
        return Step(name, None, (), draw(network(name, names, depth - 1)))
    applicable = draw(st.lists(st.lists(st.sampled_from(names), min_size=1, unique=True), max_size=3))
    rows = {sum(1 << names.index(n) for n in app): app for app in applicable}
    fusion = tuple(FusionRow(bac=b, weights={n: draw(weight) for n in app}) for b, app in rows.items())
    default = draw(st.none() | weights(names))
    landmark = draw(st.none() | st.just(Landmark("opening", "left", nth=1, odometry_m=5.0)))
    return Step(name, None, fusion, None, default, landmark)


@st.composite
def tables(draw: st.DrawFn) -> FusionTable:
    names = tuple(n for n in NAMES if n == "avoid" or draw(st.booleans()))
    return FusionTable(names, draw(weights(names)), draw(network("step", names, 2)))


def _leaves(net: Network) -> list[Step]:
    out: list[Step] = []
    for s in net.steps:
        out += _leaves(s.network) if s.network is not None else [s]
    return out


def _safe(w: dict[str, float], names: tuple[str, ...]) -> bool:
    return all(w.get(n, 0.0) >= f for n, f in FLOOR.items() if n in names)


@settings(max_examples=150, deadline=None)
@given(tables())
def test_safe_defaults_floor_the_fixed_behaviours_and_keep_every_row(t: FusionTable) -> None:
    s = safe_defaults(t)
    assert s.behaviors == t.behaviors
    assert _safe(s.default_weights, t.behaviors)
    old, new = _leaves(t.network), _leaves(s.network)
    assert len(old) == len(new)
    for a, b in zip(old, new, strict=True):
        assert (b.name, b.fusion, b.landmark) == (a.name, a.fusion, a.landmark)
        if a.default_weights is None:
            assert b.default_weights is None
            continue
        assert b.default_weights is not None and _safe(b.default_weights, t.behaviors)
        # the others as they were; a fixed one only raised, to its floor
        for k, v in a.default_weights.items():
            assert b.default_weights[k] == (max(v, FLOOR[k]) if k in FLOOR else v)
        assert set(b.default_weights) - set(a.default_weights) <= set(FLOOR)
    assert safe_defaults(s) == s


@settings(max_examples=60, deadline=None)
@given(tables())
def test_safe_defaults_survive_the_yaml_round_trip(t: FusionTable) -> None:
    s = safe_defaults(t)
    back = parse_table(yaml.safe_load(dump_table(s)))
    assert safe_defaults(back) == back


@settings(max_examples=100, deadline=None)
@given(tables())
def test_step_changes_say_where_the_weights_for_unseen_bacs_changed(t: FusionTable) -> None:
    s = safe_defaults(t)
    lines = step_changes(t, s)
    for was, now in zip(t.network.steps, s.network.steps, strict=True):
        k = sum(
            a.default_weights != b.default_weights
            for a, b in zip(_leaves(Network("", (was,))), _leaves(Network("", (now,))), strict=True)
        )
        said = [ln for ln in lines if ln.startswith(f"{was.name}:")]
        if k:
            assert said == [
                f"{was.name}: re-weights 0 row(s), adds 0 row(s); its weights for unseen BACs changed in {k} step(s)"
            ], lines
        else:
            assert not said, lines
