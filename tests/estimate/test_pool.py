"""Pooling demos: goal matching, corrections that change only the rows they touch,
the real CLI end to end."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from lfdfuse.cli.main import app
from lfdfuse.estimate.demo_alignment import align
from lfdfuse.evaluate.holdout import _wrap, predict
from lfdfuse.learn import demonstrate, learn
from lfdfuse.log import LogWriter, lfd
from lfdfuse.log.messages import RawMessage
from lfdfuse.log.reader import iter_raw
from lfdfuse.network.table import FusionRow, FusionTable, load_table
from lfdfuse.segment.goals import GoalSegment
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import SegmentedRun, read_segmented
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world

runner = CliRunner()
BEHAVIORS = "avoid,wander_left,wander_right,wall_attract_left,wall_attract_right,sonar_avoid"


def goals_run(goals: list[str | None]) -> SegmentedRun:
    """A run of two steps per goal segment, nothing but its segments (what goal matching reads)."""
    n = 2 * len(goals)
    segs = tuple(GoalSegment(i, 2 * i, 2 * i + 2, g) for i, g in enumerate(goals))
    z = np.zeros(n)
    return SegmentedRun(
        ("avoid",),
        np.arange(n, dtype=np.int64),
        np.zeros((n, 1, 2)),
        np.zeros((n, 1), dtype=bool),
        np.zeros((n, 1), dtype=bool),
        np.zeros((n, 2)),
        z.astype(bool),
        z.astype(np.int64),
        np.repeat(np.arange(len(goals)), 2),
        segs,
        {},
    )


R, G, B = "attract_red", "attract_green", "attract_blue"


@pytest.mark.parametrize(
    ("later", "goals", "steps"),
    [
        ([R, G, B, None], (R, G, B, None), (0, 1, 2, 3)),  # the same task
        ([G, B], (R, G, B, None), (1, 2)),  # a later part of it
        ([R, None], (R, G, B, None), (0, 1)),  # on its way to green when it stopped
        ([R, G, B], (R, G, B, None), (0, 1, 2)),
        ([R, B, G, None], (R, G, B, G, None), (0, 2, 3, 4)),  # green after blue: a new step there
    ],
)
def test_goal_steps_are_matched_by_goal_in_order(
    later: list[str | None], goals: tuple[str | None, ...], steps: tuple[int, ...]
) -> None:
    first = [R, G, B, None]
    al = align([goals_run(first), goals_run(later)])
    assert al.goals == goals and al.step_of[1] == steps
    # the first demo's segments keep their goals wherever its steps moved to
    assert [al.goals[j] for j in al.step_of[0]] == first


def test_a_demo_that_reached_every_goal_gets_a_goal_free_tail() -> None:
    al = align([goals_run([R, G]), goals_run([R, G, None])])
    assert al.goals == (R, G, None) and al.step_of == ((0, 1), (0, 1, 2))


# ------------------------------------------------------------------------------ corrections


def with_authority(src: Path, out: Path, *, person_from_s: float | None) -> None:
    """``src`` with a ``/lfd/authority`` channel (a ``teleop --table`` log's, DESIGN §5): the
    network drives before ``person_from_s``, the person after (None: the network throughout)."""
    raws = list(iter_raw(src))
    scans = [r.log_time_ns for r in raws if r.topic == "/scan"]
    with LogWriter(out, metadata={"teacher": "human", "command": "teleop --table"}) as log:
        for r in raws:
            log.copy(r)
        for t in scans:
            who = "person" if person_from_s is not None and t >= person_from_s * 1e9 else "network"
            data = lfd.encode_authority(t, who, "test")
            log.copy(
                RawMessage("/lfd/authority", "lfdfuse.Authority", "jsonschema", b"{}", "json", t, t, data)
            )


def rows_of(table: FusionTable) -> dict[tuple[str, int], FusionRow]:
    return {(s.name, r.bac): r for s in table.network.steps for r in s.fusion}


@pytest.fixture(scope="module")
def correction(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A keep-left demo, and a keep-right run of which the person drove only the second half."""
    d = tmp_path_factory.mktemp("corr")
    world = load_world("tee")
    demo = demonstrate(
        (Leg(None, "keep-left"),),
        world=world,
        folder=d,
        name="demo",
        duration_s=40.0,
        seed=1,
        behaviors=BEHAVIORS,
    )
    other = demonstrate(
        (Leg(None, "keep-right"),),
        world=world,
        folder=d,
        name="raw",
        duration_s=40.0,
        seed=2,
        behaviors=BEHAVIORS,
    )
    with_authority(other.raw, d / "corr.mcap", person_from_s=25.0)
    with_authority(other.raw, d / "net.mcap", person_from_s=None)
    for name in ("corr", "net"):
        segment_file(d / f"{name}.mcap", out=d / f"{name}.seg.mcap", behaviors=BEHAVIORS, measure_lag=False)
    return {"demo": demo.segmented, "corr": d / "corr.seg.mcap", "net": d / "net.seg.mcap", "dir": d}


def test_segment_marks_the_networks_ticks_non_informative(correction: dict[str, Path]) -> None:
    corr, raw = read_segmented(correction["corr"]), read_segmented(correction["dir"] / "raw.seg.mcap")
    net = corr.t_ns < 25e9
    assert not corr.informative[net].any()
    assert np.array_equal(corr.informative[~net], raw.informative[~net]) and raw.informative[net].any()
    assert corr.metadata["segment_network_ticks"] == str(int(net.sum()))
    assert not read_segmented(correction["net"]).informative.any()


def test_a_correction_is_read_by_the_persons_own_command_model(
    correction: dict[str, Path], tmp_path: Path
) -> None:
    """Only the person's commands decide the command model: keys pressed in a keyboard
    correction are discrete (the network's ticks between them take hundreds of values), and a
    person driving on the drive mapping stays continuous."""
    from tests.sources.teleop.correction import correction_log

    keys, _person = correction_log(tmp_path)
    segment_file(keys, out=tmp_path / "keys.seg.mcap", behaviors=BEHAVIORS, measure_lag=False)
    seg = read_segmented(tmp_path / "keys.seg.mcap")
    net = int(seg.metadata["segment_network_ticks"])
    assert seg.metadata["segment_commands"] == "discrete" and net > len(seg.t_ns) // 2
    assert read_segmented(correction["corr"]).metadata["segment_commands"] == "continuous"


def test_a_correction_changes_only_the_rows_the_person_drove_in(correction: dict[str, Path]) -> None:
    alone = learn([correction["demo"]]).table
    pooled = learn([correction["demo"], correction["corr"]]).table
    corr = read_segmented(correction["corr"])
    touched = {int(b) for b in corr.bac[corr.informative]}  # one goal-free step: the BACs are the rows
    before, after = rows_of(alone), rows_of(pooled)
    changed = {k for k, r in after.items() if r.samples_added}
    assert changed and {b for _, b in changed} == touched
    for key, row in after.items():
        if key in changed:
            added = int((corr.bac[corr.informative] == key[1]).sum())
            assert (
                row.samples_added == added
                and row.samples == (before[key].samples if key in before else 0) + added
            )
            assert row.weights_before == (before[key].weights if key in before else None)
        else:
            assert row == before[key]  # bit-identical: its own random stream, its own steps
    assert set(before) <= set(after)
    assert pooled.estimated_by["sources"] == ["demo.seg.mcap", "corr.seg.mcap"]
    # the network's own ticks teach nothing: a run it drove throughout leaves every row as it was
    same = learn([correction["demo"], correction["net"]]).table
    assert same.network == alone.network and same.default_weights == alone.default_weights


def test_the_cli_pools_and_lists_the_changes(correction: dict[str, Path]) -> None:
    d = correction["dir"]
    res = runner.invoke(
        app, ["estimate", str(correction["demo"]), str(correction["corr"]), "-o", str(d / "t.yaml")]
    )
    assert res.exit_code == 0, res.output
    assert "2 demos" in res.output and "samples" in res.output and "→" in res.output
    table = load_table(d / "t.yaml")
    assert table.estimated_by["sources"] == ["demo.seg.mcap", "corr.seg.mcap"]
    res = runner.invoke(app, ["inspect", str(d / "t.yaml")])
    assert res.exit_code == 0 and "pooled 2 demos" in res.output and "→" in res.output
    res = runner.invoke(app, ["inspect", str(correction["corr"])])
    assert res.exit_code == 0 and "correction log" in res.output
    # demos segmented with other behaviours cannot be pooled: one line, exit 1
    segment_file(d / "corr.mcap", out=d / "few.seg.mcap", behaviors="avoid,wander_left", measure_lag=False)
    res = runner.invoke(
        app, ["estimate", str(correction["demo"]), str(d / "few.seg.mcap"), "-o", str(d / "x.yaml")]
    )
    assert res.exit_code == 1 and res.output.startswith("error:") and not (d / "x.yaml").exists()


# ------------------------------------------------------------------------------ several demos of one style


def test_three_demos_pooled_predict_a_fourth_better_than_any_one(tmp_path: Path) -> None:
    """Three short keep-left demos by a person at a keyboard (``simulate --keys 0.8``) from
    different starts, pooled, predict a fourth (all of its steps are held out: it trained nothing)
    better than each alone; the pooled rows are narrower where it counts (the posterior std summed
    over every row's weights, by its samples). Measured: singles 24.9°, 27.5°, 24.1°, pooled
    20.5°; std ratio median 0.53 over 10 rows."""
    world = load_world("tee")
    starts = [(1.0, 9.0, 0.0), (15.0, 2.0, 3.14), (7.0, 6.0, 1.57), (28.0, 9.0, 3.14)]
    segs = [
        demonstrate(
            (Leg(None, "keep-left"),),
            world=world,
            folder=tmp_path,
            name=f"d{i}",
            duration_s=40.0 if i < 3 else 60.0,
            seed=i + 1,
            start=st,
            behaviors=BEHAVIORS,
            keys_period_s=0.8,
        ).segmented
        for i, st in enumerate(starts)
    ]
    test = read_segmented(segs[3])
    steps = np.nonzero(test.informative)[0]
    demo = np.arctan2(test.demo[steps, 1], test.demo[steps, 0])

    def error(table: FusionTable) -> float:
        return float(np.degrees(np.abs(_wrap(predict(table, test, steps) - demo))).mean())

    singles = [learn([s]).table for s in segs[:3]]
    pooled = learn(segs[:3]).table
    errs = [error(t) for t in singles]
    print(f"held-out heading error: singles {[round(e, 2) for e in errs]}, pooled {error(pooled):.2f}")
    assert error(pooled) < min(errs) - 0.5
    # a row the pool gave at least twice a single demo's samples: the posterior std (summed over
    # its weights) narrows. Not on every row: where the demos disagree (one long, consistent row
    # against two others), the row's shared heading noise grows and so does its std
    pool_rows = rows_of(pooled)
    ratios = [
        sum((pool_rows[k].std or {}).values()) / sum((r.std or {}).values())
        for t in singles
        for k, r in rows_of(t).items()
        if (pool_rows[k].samples or 0) >= 2 * (r.samples or 0) > 0
    ]
    print(f"std pooled / single on the rows the pool grew: {sorted(round(x, 2) for x in ratios)}")
    assert len(ratios) >= 3 and float(np.median(ratios)) < 0.8


def test_each_demo_keeps_its_own_command_model(tmp_path: Path) -> None:
    """A scripted demo (continuous) pooled with a person's keyboard demo (discrete): each is read
    by its own model, whichever comes first — the provenance lists both, and a row both demos
    pool is the same estimate in either order (up to the sampler: the same likelihood)."""
    world = load_world("tee")
    segs = [
        demonstrate(
            (Leg(None, "keep-left"),),
            world=world,
            folder=tmp_path,
            name=name,
            duration_s=30.0,
            seed=seed,
            start=(1.0, 9.0, 0.0),
            behaviors=BEHAVIORS,
            keys_period_s=keys,
        ).segmented
        for name, seed, keys in [("scripted", 1, None), ("keys", 2, 0.8)]
    ]
    # the scripted demo first: the real command's table (learned once, read back from its file)
    res = runner.invoke(app, ["estimate", str(segs[0]), str(segs[1]), "-o", str(tmp_path / "t.yaml")])
    assert res.exit_code == 0, res.output
    assert "scripted.seg.mcap continuous, keys.seg.mcap discrete" in res.output
    one, two = load_table(tmp_path / "t.yaml"), learn(segs[::-1]).table
    assert one.estimated_by["source_commands"] == ["continuous", "discrete"]
    assert two.estimated_by["source_commands"] == ["discrete", "continuous"]
    a, b = rows_of(one), rows_of(two)
    both = [k for k in a if k in b and (a[k].samples_added or 0) > 0 and (b[k].samples_added or 0) > 0]
    assert both
    for k in both:
        gap = max(abs(a[k].weights[n] - b[k].weights[n]) for n in a[k].weights)
        assert gap < 0.1, (k, a[k].weights, b[k].weights)
