"""Faults on a live link, against a bridge-like robot running in real time (10 Hz).

Times are the robot's wall clock; tolerances beyond the contract's 0.5 s allow for this
machine's scheduling (two cores shared by many processes).
"""

from __future__ import annotations

import time
from pathlib import Path

from lfdfuse.network.table import load_table
from lfdfuse.world.model import load_world
from tests.drive.conftest import in_thread, start_drive
from tests.support.bridge_sim import BridgeSim

SLACK_S = 0.25


def test_scans_stop_the_robot_stops_within_half_a_second(keep_left: Path) -> None:
    marks: dict[str, float] = {}
    with BridgeSim(load_world("tee"), encoding="cdr", lockstep=False) as robot:
        live = start_drive(load_table(keep_left), robot.url)

        def script() -> None:
            assert robot.wait_for_subscriber()
            loop = in_thread(lambda: robot.run(5.5))
            time.sleep(2.0)
            marks["pause"] = time.monotonic()
            robot.scans_paused.set()
            time.sleep(1.5)
            robot.scans_paused.clear()
            marks["back"] = time.monotonic()
            loop.join()
            live.stopper.stop("done")

        th = in_thread(script)
        s = live.join(60)
        th.join(5)
    rx = robot.received
    before = [r for r in rx if r.wall_s < marks["pause"]]
    paused = [r for r in rx if marks["pause"] <= r.wall_s < marks["back"]]
    after = [r for r in rx if r.wall_s > marks["back"] + 0.5]
    assert any(r.v_mps > 0.1 for r in before)
    first_zero = next(r for r in paused if (r.v_mps, r.omega_rps) == (0.0, 0.0))
    assert first_zero.wall_s - marks["pause"] <= 0.5 + SLACK_S
    assert all((r.v_mps, r.omega_rps) == (0.0, 0.0) for r in paused if r.wall_s >= first_zero.wall_s)
    assert any(r.v_mps > 0.1 for r in after), "drives again once scans return"
    assert any("no fresh scan" in n for n in live.notes) and any("scans are back" in n for n in live.notes)
    assert s.zeros >= 5


def test_the_connection_drops_and_returns(keep_left: Path) -> None:
    marks: dict[str, float] = {}
    with BridgeSim(load_world("tee"), encoding="cdr", lockstep=False) as robot:
        live = start_drive(load_table(keep_left), robot.url)

        def script() -> None:
            assert robot.wait_for_subscriber()
            loop = in_thread(lambda: robot.run(6.0))
            time.sleep(2.0)
            marks["down"] = time.monotonic()
            robot.drop(1.0)
            marks["up"] = time.monotonic()
            loop.join()
            live.stopper.stop("done")

        th = in_thread(script)
        s = live.join(60)
        th.join(5)
    rx = robot.received
    assert s.connections == 2 and any("reconnected" in n for n in live.notes)
    assert not [r for r in rx if marks["down"] + 0.05 < r.wall_s < marks["up"]], "nothing while down"
    back = [r for r in rx if r.wall_s >= marks["up"]]
    assert back and (back[0].v_mps, back[0].omega_rps) == (0.0, 0.0), "a new connection starts standing still"
    assert any(r.v_mps > 0.1 for r in back), "drives again"
    assert sum("connection lost" in n for n in live.notes) == 1


def test_a_malformed_message_is_one_warning_and_the_run_goes_on(keep_left: Path) -> None:
    marks: dict[str, float] = {}
    with BridgeSim(load_world("tee"), encoding="cdr", lockstep=False) as robot:
        live = start_drive(load_table(keep_left), robot.url)

        def script() -> None:
            assert robot.wait_for_subscriber()
            loop = in_thread(lambda: robot.run(3.5))
            time.sleep(1.5)
            for _ in range(3):
                robot.inject("/scan", b"\x00\x01\x00\x00 not a LaserScan")
            marks["bad"] = time.monotonic()
            loop.join()
            live.stopper.stop("done")

        th = in_thread(script)
        s = live.join(60)
        th.join(5)
    warnings = [n for n in live.notes if n.startswith("warning:")]
    assert len(warnings) == 1 and "/scan" in warnings[0], live.notes
    assert list(s.warnings.values()) == [3]
    assert any(r.v_mps > 0.1 for r in robot.received if r.wall_s > marks["bad"] + 0.3)
    assert s.connections == 1
