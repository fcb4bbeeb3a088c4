"""The scripted person takes over where the robot left the teacher's path."""

from __future__ import annotations

import numpy as np

from tests.support.corrections import INTO_GOAL_M, LEAVE_M, STALL_S, CorrectionPlan, correction_plan

DT_S = 0.1
STEP_M = 0.04  # 0.4 m/s
DEAD_END_M = 6.0


def _line(a: tuple[float, float], b: tuple[float, float]) -> np.ndarray:
    n = max(int(round(np.hypot(b[0] - a[0], b[1] - a[1]) / STEP_M)), 1)
    return np.linspace(a, b, n, endpoint=False)


TEACHER = np.concatenate([_line((0.0, 0.0), (20.0, 0.0)), [[20.0, 0.0]]])


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
    lap = np.concatenate(
        [
            _line((0.0, 0.0), (8.0, 0.0)),
            _line((8.0, 0.0), (8.0, DEAD_END_M)),
            _line((8.0, DEAD_END_M), (8.0, 0.0)),
            _line((8.0, 0.0), (0.0, 0.0)),
            _line((0.0, 0.0), (20.0, 0.0)),
        ]
    )
    assert DEAD_END_M > LEAVE_M
    plan = correction_plan(TEACHER, lap, DT_S)
    assert plan is not None
    x_take, y_take = lap[round(plan.take_s / DT_S)]
    assert 6.5 < x_take <= 8.0 and y_take == 0.0
    assert plan.path_xy[0, 0] < 8.0 and plan.path_xy[-1, 0] > 12.0


def test_a_robot_that_turns_round_in_a_dead_end_and_drives_on_is_not_corrected() -> None:
    out_and_on = np.concatenate(
        [
            _line((0.0, 0.0), (8.0, 0.0)),
            _line((8.0, 0.0), (8.0, DEAD_END_M)),
            _line((8.0, DEAD_END_M), (8.0, 0.0)),
            _line((8.0, 0.0), (20.0, 0.0)),
            [[20.0, 0.0]],
        ]
    )
    assert correction_plan(TEACHER, out_and_on, DT_S) is None


def test_a_robot_that_dithers_is_taken_over_where_it_stalled() -> None:
    # a minute to and fro over half a metre, then on along the path: stalled, not following
    dither = np.concatenate([_line((8.0, 0.0), (8.3, 0.0)), _line((8.3, 0.0), (8.0, 0.0))] * 40)
    robot = np.concatenate([_line((0.0, 0.0), (8.0, 0.0)), dither, _line((8.0, 0.0), (20.0, 0.0))])
    assert len(dither) * DT_S > STALL_S
    plan = correction_plan(TEACHER, robot, DT_S)
    assert plan is not None
    assert 6.5 < robot[round(plan.take_s / DT_S), 0] <= 8.3


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


def test_a_robot_that_drove_past_the_last_goal_at_the_paths_end_is_brought_to_it() -> None:
    # the teacher's path ends at the last goal; the robot drives along it a metre aside (within
    # the path's reach, out of the camera's) and on past it, never reaching it: the person takes
    # over before the goal and drives to where the teacher reached it
    goal_at = len(TEACHER) - 1
    robot = np.concatenate([_line((0.0, 0.8), (30.0, 0.8)), np.full((300, 2), [30.0, 0.8])])
    assert correction_plan(TEACHER, robot, DT_S) is None  # it met every point of the path
    assert correction_plan(TEACHER, robot, DT_S, goals_at=[goal_at], reached_at=[goal_at]) is None
    plan = correction_plan(TEACHER, robot, DT_S, goals_at=[goal_at], reached_at=[])
    assert plan is not None and len(plan.stops) == 1
    assert robot[round(plan.take_s / DT_S), 0] < TEACHER[goal_at, 0]
    assert _drives_into(plan, TEACHER[goal_at])
