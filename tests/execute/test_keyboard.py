"""Closed loop: what a person at a keyboard teaches is learned.

The scripted teacher becomes a person at a keyboard (``simulate --keys``: the nearest teleop key
every period, jittered, held); the demo is segmented and estimated with the command line's
defaults (``--lag auto``, ``--commands auto``: the discrete command model at the press lag) and
the learned table drives. ``make bench`` (suite ``keys``) measures the same cases over more
seeds and the whole zoo; here the three-goal table learned at keys every 1.0 s (seed 1) must
complete at least 2 of 3 perturbed starts, and each style table must take its own branch at
every tee; persons of the zoo (``simulate --person``) teach the three-goal task and the styles
too.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from lfdfuse.sim.loop import RunSummary
from lfdfuse.sources.tasks import Leg, load_task
from tests.bench.keys import (
    STYLE_BEHAVIORS,
    TASK,
    demo_completed,
    execute_starts,
    learn,
    tee_branches,
    three_goal_starts,
    three_goals,
)


def test_keyboard_taught_three_goal_task_completes(tmp_path: Path) -> None:
    table = learn(load_task(str(TASK)), world="building", keys=1.0, seed=1, folder=tmp_path)
    assert table.estimated_by["commands"] == "discrete"
    done = three_goals(table, starts=three_goal_starts(3, seed=2026), folder=tmp_path, label="k")
    assert sum(done) >= 2, done


def test_keyboard_taught_styles_take_their_branch_in_another_world(tmp_path: Path) -> None:
    for style in ("keep-left", "keep-right"):
        table = learn(
            [Leg(None, style)],
            world="building",
            keys=0.8,
            seed=1,
            folder=tmp_path,
            duration_s=300.0,
            segment_kw={"behaviors": STYLE_BEHAVIORS},
        )
        got = tee_branches(table, folder=tmp_path, label=style)
        assert got == [style == "keep-left"] * len(got), (style, got)


def test_zoo_taught_styles_take_their_branch(tmp_path: Path) -> None:
    """Two persons of the zoo other than ``--keys``'s own: a coarse one (a key every 1.2 s, chosen
    by thresholds on the wanted turn) teaches keep-left, a prompt one (a key every 0.3 s, no
    delay) keep-right; each learned table takes its own branch at both tees (``make bench`` runs
    the whole zoo, where some persons do not yet teach every style)."""
    for person, style in (("coarse", "keep-left"), ("prompt", "keep-right")):
        table = learn(
            [Leg(None, style)],
            world="building",
            keys=None,
            person=person,
            seed=11,
            folder=tmp_path,
            duration_s=300.0,
            segment_kw={"behaviors": STYLE_BEHAVIORS},
        )
        got = tee_branches(table, folder=tmp_path, label=f"{person}-{style}")
        assert got == [style == "keep-left"] * len(got), (person, style, got)


@pytest.mark.parametrize("person", ["late", "corner-cutter"])
def test_zoo_persons_teach_the_three_goal_task(tmp_path: Path, person: str) -> None:
    """Two persons of the zoo: late (0.6 s late, a key every 0.8 s) and corner-cutter (aims 2 m
    farther along the route) complete their own three-goal demo without a collision, and the
    table learned from it completes the task from a perturbed start (``make bench`` runs every
    person, 2 seeds × 3 starts)."""
    demos: list[RunSummary] = []
    table = learn(
        load_task(str(TASK)),
        world="building",
        keys=None,
        person=person,
        seed=11,
        folder=tmp_path,
        demos=demos,
    )
    assert demo_completed(demos[0]), demos[0]
    done = three_goals(table, starts=execute_starts(1, seed=11), folder=tmp_path, label=person)
    assert done == [True], (person, done)
