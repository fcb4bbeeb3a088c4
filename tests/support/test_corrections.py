"""The scripted person takes over where the robot left the teacher's path."""

from __future__ import annotations

import json
from collections.abc import Callable

import numpy as np
import pytest

from lfdfuse.robot.pose import Pose
from tests.support.corrections import (
    BACK_S,
    INTO_GOAL_M,
    LEAD_S,
    LEAVE_M,
    PAST_M,
    STALL_S,
    STRAY_S,
    STUCK_S,
    CorrectionPlan,
    PathPerson,
    correction_plan,
)

DT_S = 0.1
STEP_M = 0.04  # 0.4 m/s
DEAD_END_M = 4.0  # in and out again in 20 s at 0.4 m/s: not lost there


def _line(a: tuple[float, float], b: tuple[float, float]) -> np.ndarray:
    n = max(int(round(np.hypot(b[0] - a[0], b[1] - a[1]) / STEP_M)), 1)
    return np.linspace(a, b, n, endpoint=False)


TEACHER = np.concatenate([_line((0.0, 0.0), (20.0, 0.0)), [[20.0, 0.0]]])
#: into a dead end at 8 m the teacher passed by, round, back the way it came and a lap later along
#: the path
DEAD_END_LAP = np.concatenate(
    [
        _line((0.0, 0.0), (8.0, 0.0)),
        _line((8.0, 0.0), (8.0, DEAD_END_M)),
        _line((8.0, DEAD_END_M), (8.0, 0.0)),
        _line((8.0, 0.0), (0.0, 0.0)),
        _line((0.0, 0.0), (20.0, 0.0)),
    ]
)
#: into that dead end, back out and on along the path
DEAD_END_AND_ON = np.concatenate(
    [
        _line((0.0, 0.0), (8.0, 0.0)),
        _line((8.0, 0.0), (8.0, DEAD_END_M)),
        _line((8.0, DEAD_END_M), (8.0, 0.0)),
        _line((8.0, 0.0), (20.0, 0.0)),
        [[20.0, 0.0]],
    ]
)


def test_a_robot_that_follows_the_path_within_the_corridor_is_not_corrected() -> None:
    robot = TEACHER + np.array([0.0, 0.8])  # a metre aside, all the way
    assert correction_plan(TEACHER, robot, DT_S) is None


def test_a_robot_that_stops_short_is_taken_over_where_it_stopped() -> None:
    robot = np.concatenate([_line((0.0, 0.0), (8.0, 0.0)), np.full((500, 2), [8.0, 0.0])])
    plan = correction_plan(TEACHER, robot, DT_S)
    assert plan is not None
    x_take = robot[round(plan.take_s / DT_S), 0]
    assert 6.5 < x_take < 8.0
    assert plan.path_xy[0, 0] < 8.0 < plan.path_xy[-1, 0]


def test_a_robot_that_comes_back_from_a_dead_end_the_wrong_way_is_taken_over_at_its_mouth() -> None:
    # into a dead end the teacher passed by, round, back the way it came and, a lap later, along
    # the path: the points it meets after the lap are not followed; the person takes over
    # before the dead end
    lap = DEAD_END_LAP
    assert DEAD_END_M > LEAVE_M
    plan = correction_plan(TEACHER, lap, DT_S)
    assert plan is not None
    x_take, y_take = lap[round(plan.take_s / DT_S)]
    assert 6.5 < x_take <= 8.0 and y_take == 0.0
    assert plan.path_xy[0, 0] < 8.0 and plan.path_xy[-1, 0] > 12.0


def test_a_robot_that_turns_round_in_a_dead_end_and_drives_on_is_not_corrected() -> None:
    out_and_on = DEAD_END_AND_ON
    assert correction_plan(TEACHER, out_and_on, DT_S) is None


def test_a_robot_lost_in_a_dead_end_is_taken_over_where_it_turned_off_though_it_came_back() -> None:
    # into the dead end, half a minute to and fro at its end wall, back out and on along the path
    dither = np.concatenate(
        [_line((8.0, DEAD_END_M), (8.0, DEAD_END_M - 0.3)), _line((8.0, DEAD_END_M - 0.3), (8.0, DEAD_END_M))]
        * 20
    )
    lost = np.concatenate(
        [
            DEAD_END_AND_ON[: int(np.argmax(DEAD_END_AND_ON[:, 1]))],
            dither,
            DEAD_END_AND_ON[int(np.argmax(DEAD_END_AND_ON[:, 1])) :],
        ]
    )
    assert len(dither) * DT_S > STRAY_S
    plan = correction_plan(TEACHER, lost, DT_S)
    assert plan is not None
    x_take, y_take = lost[round(plan.take_s / DT_S)]
    assert 6.0 < x_take <= 8.0 and y_take < 0.5  # before the mouth, not inside
    assert plan.path_xy[0, 0] <= 8.0 and plan.path_xy[-1, 0] > 8.0 + PAST_M - 1.0


def test_a_robot_that_dithers_is_taken_over_where_it_stalled() -> None:
    # a minute to and fro over half a metre, then on along the path: stalled, not following
    dither = np.concatenate([_line((8.0, 0.0), (8.3, 0.0)), _line((8.3, 0.0), (8.0, 0.0))] * 40)
    robot = np.concatenate([_line((0.0, 0.0), (8.0, 0.0)), dither, _line((8.0, 0.0), (20.0, 0.0))])
    assert len(dither) * DT_S > STALL_S
    plan = correction_plan(TEACHER, robot, DT_S)
    assert plan is not None
    assert 6.5 < robot[round(plan.take_s / DT_S), 0] <= 8.3


def test_a_robot_that_follows_the_path_and_hits_a_wall_is_taken_over_before_it() -> None:
    # within the corridor all the way (not corrected), but it brushed a wall 12 m along: the
    # person takes over LEAD_S before and drives the teacher's path past where it hit
    robot = TEACHER + np.array([0.0, 0.8])
    hit = int(np.searchsorted(robot[:, 0], 12.0))
    assert correction_plan(TEACHER, robot, DT_S) is None
    plan = correction_plan(TEACHER, robot, DT_S, hit_at=hit)
    assert plan is not None
    assert round(plan.take_s / DT_S) == hit - round(LEAD_S / DT_S)
    x_take = robot[round(plan.take_s / DT_S), 0]
    assert plan.path_xy[0, 0] == pytest.approx(x_take, abs=STEP_M)
    assert plan.path_xy[-1, 0] == pytest.approx(12.0 + PAST_M, abs=STEP_M)


def test_a_robot_that_left_the_path_before_it_hit_a_wall_keeps_that_takeover() -> None:
    # into a dead end (as above), where it hits the wall at the end: the person takes over at
    # the mouth, where it left the path, and a wall hit before it left is taken over there
    lap = DEAD_END_LAP
    left = correction_plan(TEACHER, lap, DT_S)
    assert left is not None
    in_dead_end = int(np.argmax(lap[:, 1]))
    kept = correction_plan(TEACHER, lap, DT_S, hit_at=in_dead_end)
    assert kept is not None and kept.take_s == left.take_s and np.array_equal(kept.path_xy, left.path_xy)
    before = len(_line((0.0, 0.0), (4.0, 0.0)))
    plan = correction_plan(TEACHER, lap, DT_S, hit_at=before)
    assert plan is not None and plan.take_s < left.take_s
    assert plan.path_xy[-1, 0] == pytest.approx(4.0 + PAST_M, abs=STEP_M)


def test_a_robot_that_hits_a_wall_in_a_dead_end_it_came_back_out_of_is_taken_over_before_it() -> None:
    # into a dead end the teacher passed by, against its end wall, back out and on along the
    # path (not corrected alone): the person takes over before the robot turned off the path
    # and drives the path on past the dead end's mouth
    out_and_on = DEAD_END_AND_ON
    assert correction_plan(TEACHER, out_and_on, DT_S) is None
    plan = correction_plan(TEACHER, out_and_on, DT_S, hit_at=int(np.argmax(out_and_on[:, 1])))
    assert plan is not None
    x_take, y_take = out_and_on[round(plan.take_s / DT_S)]
    assert 6.0 < x_take <= 8.0 and y_take < 0.5  # at the mouth, not inside
    assert plan.path_xy[0, 0] <= 8.0 and plan.path_xy[-1, 0] > 8.0 + PAST_M - 1.0


def _spur_to_a_goal() -> tuple[np.ndarray, int]:
    """The teacher drives up a spur to a goal at its end and back, then on: its path and the
    tick it reached the goal."""
    up = [_line((0.0, 0.0), (8.0, 0.0)), _line((8.0, 0.0), (8.0, 4.0))]
    teacher = np.concatenate([*up, _line((8.0, 4.0), (8.0, 0.0)), TEACHER[200:]])
    return teacher, sum(len(a) for a in up)


def _drives_into(plan: CorrectionPlan, goal_xy: np.ndarray) -> bool:
    """The person drives to the teacher's place at the goal, then on into it, and stops there."""
    (stop,) = plan.stops
    return bool(
        np.allclose(plan.path_xy[stop - 1], goal_xy)
        and np.isclose(np.hypot(*(plan.path_xy[stop] - goal_xy)), INTO_GOAL_M)
    )


def test_the_teachers_path_at_a_goal_need_not_be_met() -> None:
    # the robot reaches the goal from a metre and a half short of where the teacher turned
    teacher, goal_at = _spur_to_a_goal()
    robot = np.concatenate(
        [
            _line((0.0, 0.0), (8.0, 0.0)),
            _line((8.0, 0.0), (8.0, 2.6)),
            _line((8.0, 2.6), (8.0, 0.0)),
            TEACHER[200:],
        ]
    )
    assert correction_plan(teacher, robot, DT_S) is not None  # the spur's end missed
    assert correction_plan(teacher, robot, DT_S, goals_at=[goal_at]) is None
    # ... where it reached it: a robot that never did must meet the spur's end as the teacher did
    assert correction_plan(teacher, robot, DT_S, goals_at=[goal_at], reached_at=[]) is not None


def test_the_person_drives_to_where_the_teacher_reached_a_goal() -> None:
    teacher, goal_at = _spur_to_a_goal()
    robot = np.concatenate([_line((0.0, 0.0), (7.0, 0.0)), np.full((500, 2), [7.0, 0.0])])  # stops short
    plan = correction_plan(teacher, robot, DT_S, goals_at=[goal_at])
    assert plan is not None and len(plan.stops) == 1
    assert _drives_into(plan, teacher[goal_at])


def test_a_robot_that_drove_to_a_goal_without_reaching_it_is_brought_to_it() -> None:
    # the robot drives the teacher's path up the spur and back (its camera never saw the goal):
    # the person takes over before the goal and drives to where the teacher reached it
    teacher, goal_at = _spur_to_a_goal()
    assert correction_plan(teacher, teacher, DT_S, goals_at=[goal_at]) is None  # it reached the goal
    plan = correction_plan(teacher, teacher, DT_S, goals_at=[goal_at], reached_at=[])
    assert plan is not None and len(plan.stops) == 1
    assert plan.take_s < goal_at * DT_S
    assert _drives_into(plan, teacher[goal_at])


def test_the_person_starts_on_the_way_into_a_spur_not_on_the_way_out() -> None:
    # the teacher drove up a spur to a goal and back down beside its way up; the robot drives up
    # where the teacher came down, reaches the goal from the spur's middle (its camera sees it
    # there) and stops: the person takes over on the teacher's way in, which the robot had not
    # left, and drives to the teacher's place at the goal
    up = [_line((0.0, 0.0), (8.0, 0.0)), _line((8.0, 0.0), (8.0, 4.0))]
    teacher = np.concatenate([*up, _line((8.4, 4.0), (8.4, 0.0)), _line((8.4, 0.0), (20.0, 0.0))])
    goal_at = sum(len(a) for a in up)
    stop = np.full((500, 2), [8.4, 2.4])
    robot = np.concatenate([_line((0.0, 0.0), (8.4, 0.0)), _line((8.4, 0.0), (8.4, 2.4)), stop])
    plan = correction_plan(teacher, robot, DT_S, goals_at=[goal_at], reached_at=[len(robot) - len(stop)])
    assert plan is not None
    assert plan.path_xy[0, 0] == 8.0  # on the teacher's way up
    assert len(plan.stops) == 1 and _drives_into(plan, teacher[goal_at])


def test_a_robot_that_drove_past_a_goal_and_reached_it_only_coming_round_again_is_brought_to_it() -> None:
    # the robot drives past the goal (its camera never saw it), round a loop and back along the
    # path, where it reaches the goal the second time: the person takes over on the first pass,
    # before the goal, and drives to where the teacher reached it
    goal_at = len(_line((0.0, 0.0), (10.0, 0.0)))
    first = _line((0.0, 0.0), (20.0, 0.0))
    loop = [
        _line((20.0, 0.0), (20.0, 10.0)),
        _line((20.0, 10.0), (0.0, 10.0)),
        _line((0.0, 10.0), (0.0, 0.0)),
    ]
    robot = np.concatenate([first, *loop, TEACHER])
    again = len(robot) - len(TEACHER) + goal_at
    assert correction_plan(TEACHER, robot, DT_S, goals_at=[goal_at], reached_at=[len(first) // 3]) is None
    plan = correction_plan(TEACHER, robot, DT_S, goals_at=[goal_at], reached_at=[again])
    assert plan is not None and len(plan.stops) == 1
    assert plan.take_s < goal_at * DT_S
    assert _drives_into(plan, TEACHER[goal_at])


def test_a_robot_that_meets_the_way_out_of_a_spur_on_its_way_in_is_not_corrected() -> None:
    # the teacher drove up a spur to a goal and back down beside its way up; the robot drives up
    # where the teacher came down (meeting the way out before it reaches the goal), reaches the
    # goal at the spur's end and drives on as the teacher did
    up = [_line((0.0, 0.0), (8.0, 0.0)), _line((8.0, 0.0), (8.0, 4.0))]
    down = [_line((8.4, 4.0), (8.4, 0.0)), _line((8.4, 0.0), (20.0, 0.0)), [[20.0, 0.0]]]
    teacher = np.concatenate([*up, *down])
    goal_at = sum(len(a) for a in up)
    robot = np.concatenate([_line((0.0, 0.0), (8.4, 0.0)), _line((8.4, 0.0), (8.4, 4.0)), *down])
    reached = len(robot) - sum(len(a) for a in down)
    assert correction_plan(teacher, robot, DT_S, goals_at=[goal_at], reached_at=[reached]) is None


class _Snapshot:
    def __init__(self, pose: Pose) -> None:
        self.pose = pose


class _Session:
    snapshot: _Snapshot


def _drive(person: PathPerson, poses: Callable[[float], Pose], until_s: float) -> list[float]:
    """The speeds ``person`` commands each 0.1 s to ``until_s`` with the robot at ``poses(t)``."""
    session = _Session()
    person.session = session  # type: ignore[assignment]
    speeds = []
    for k in range(round(until_s / DT_S)):
        t = k * DT_S
        session.snapshot = _Snapshot(poses(t))
        got = person.poll(t)
        if got and got[0].kind == "message":
            speeds.append(float(json.loads(got[0].text)["linear"]["x"]))
    return speeds


def test_a_person_whose_robot_does_not_move_backs_off_and_drives_on() -> None:
    plan = CorrectionPlan(0.0, TEACHER)
    pinned = _drive(PathPerson(plan), lambda t: Pose(0.0, 0.0, 0.0), 6.0)
    stuck = round(STUCK_S / DT_S)  # a pose STUCK_S old is there to compare with from then on
    assert all(v > 0 for v in pinned[:stuck])
    assert all(v < 0 for v in pinned[stuck : stuck + round(BACK_S / DT_S)])
    assert pinned[stuck + round(BACK_S / DT_S)] > 0
    moving = _drive(PathPerson(plan), lambda t: Pose(0.3 * t, 0.0, 0.0), 6.0)
    assert all(v > 0 for v in moving)


def test_a_robot_that_met_the_whole_path_but_passed_its_last_goal_by_is_brought_to_it() -> None:
    # the teacher's path ends where it reached its last goal; the robot drives it half a metre
    # to the side (meeting every point of it) and its camera never reaches the goal
    goal_at = len(TEACHER) - 1
    robot = np.concatenate([TEACHER + [0.0, 0.5], _line((20.0, 0.5), (26.0, 0.5))])
    assert correction_plan(TEACHER, robot, DT_S, goals_at=[goal_at], reached_at=[goal_at]) is None
    plan = correction_plan(TEACHER, robot, DT_S, goals_at=[goal_at], reached_at=[])
    assert plan is not None and len(plan.stops) == 1
    assert plan.take_s < goal_at * DT_S
    assert _drives_into(plan, TEACHER[goal_at])


def test_a_person_who_watches_on_takes_over_again_at_the_next_plan() -> None:
    first = CorrectionPlan(0.0, TEACHER[:50])  # 2 m, driven at SPEED_MPS
    again = CorrectionPlan(12.0, TEACHER[200:260])
    person = PathPerson(first, [again])
    session = _Session()
    person.session = session  # type: ignore[assignment]
    kinds: list[tuple[float, str]] = []
    x = 0.0
    for k in range(round(20.0 / DT_S)):
        t = k * DT_S
        session.snapshot = _Snapshot(Pose(x, 0.0, 0.0))
        got = person.poll(t)
        kinds += [(t, g.kind) for g in got]
        if got and got[0].kind == "message":  # the robot drives as told
            x += float(json.loads(got[0].text)["linear"]["x"]) * DT_S
        elif t >= 5.0 and x < 8.0:
            x = 8.0  # the network drove on to the second place
    backs = [t for t, kind in kinds if kind == "handback"]
    assert len(backs) == 2 and backs[0] < again.take_s <= backs[1]
    # nothing between the first hand-back and the second takeover
    assert not [t for t, _ in kinds if backs[0] < t < again.take_s - 1e-9]
    assert person.handed_back_s == backs[1]
