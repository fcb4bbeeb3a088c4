"""A scripted person who corrects a learned table where its robot left the teacher's path or hit a wall.

Given a failed run of the table (its log) and the teacher's path, :func:`correction_plan` finds
where the robot left the path: the last point of the teacher's path it met in order (as
:func:`lfdfuse.execute.check.follow` counts them) before it strayed :data:`LEAVE_M` from the
stretch of the path since (into a dead end the teacher passed by, round the wrong way) or took
:data:`STALL_S` to meet the next (dithering): a point it meets only after coming back is not
followed. A robot that strayed and came back to the path within :data:`STRAY_S` and drove on
along it is not corrected there; one that came back later was lost there (a person watching
would not have waited). Where the teacher reached a goal the robot reached too, the points within
:data:`GOAL_M` of it need not be met (the robot reaches a goal from where its camera sees it);
a robot that met the path past a goal before it reached it (only coming round again) missed it
there, and so did a robot that met the path all the way but never reached a goal on it (drove
past it out of the camera's reach). A robot that hit a wall before it left the path so (the log
keeps no collisions: :func:`lfdfuse.evaluate.plot_data.contacts` reads where a contact began) is
taken over before it: a person takes over before the wall, not after. Where it hit the wall
beside the path, the place is the wall; where it hit one off the path (in a dead end it turned
into and came back out of, which alone is not corrected), the place is where it last was on the
path, before it turned off. :func:`record_correction` then runs ``teleop --table`` from the same
start and seed — tick for tick the failed run until the person takes over — and a
:class:`PathPerson` takes over a little (:data:`LEAD_S`) before that place, drives the teacher's
path (pure pursuit, as a Twist client would) through the place and :data:`PAST_M` past it, and
hands back; the network drives on. A robot the person drives into a wall (pursuit cutting a
corner) is backed off and the path followed tighter. One correction is one takeover; a person
who watches on (``takeovers`` > 1) takes over again where the network, handed back, leaves the
teacher's path again.
The log is segmented with the table's behaviours.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from lfdfuse.evaluate.plot_data import contacts
from lfdfuse.execute.check import path_points
from lfdfuse.execute.correct import correct, correction_driver
from lfdfuse.log import lfd
from lfdfuse.log.reader import iter_messages, read_run
from lfdfuse.log.run import hold
from lfdfuse.network.table import FusionTable
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.sources.teleop.clock import SimClock
from lfdfuse.sources.teleop.inputs import Input
from lfdfuse.sources.teleop.script import SOURCE, TWIST_SCHEMA, twist_payload
from lfdfuse.sources.teleop.session import TeleopOptions, TeleopSession, make_session
from lfdfuse.world.model import World

#: the person takes over this long (s) before the robot met the last point of the path it followed
#: (or before it hit a wall)
LEAD_S = 2.0
#: and drives the teacher's path this far (m) past the first point the robot missed (or the wall)
PAST_M = 6.0
RADIUS_M = 1.0  # a path point is met within this (as the check's)
#: the robot has left the path where it is this far (m) from the stretch between the last point it
#: met and the next one
LEAVE_M = 2.5
#: or where it took this long (s) from one point of the path to the next (stalled, dithering)
STALL_S = 20.0
#: a robot that strayed from the path and came back to it later than this (s) was lost there (a
#: person watching takes over where it turned off): one that came back sooner drove on
STRAY_S = 20.0
#: the teacher's path this near (m) where it reached a goal need not be met: a robot reaches the
#: goal from where its camera sees it, and turns back from there
GOAL_M = 1.5
#: a robot that met the teacher's path this far (m of the teacher's travel) past a goal it never
#: reached drove on without it
LATE_M = 3.0
#: a robot that strayed and came back drove on along the path when it met the point this far (m)
#: past the last one it met before straying
RESUME_M = 2.5
LOOKAHEAD_M = 0.8
STOP_M = 0.3  # the teacher's place at a goal is driven to within this ...
#: ... and on past it this far (m) the way the teacher was going there: the teacher reached the
#: goal at the first tick its camera could, at the edge of the camera's reach
INTO_GOAL_M = 0.3
SPEED_MPS = 0.4
#: a person whose robot has not moved this far (m) in :data:`STUCK_S` while they drove it (pursuit
#: cut a corner into a wall) backs off for :data:`BACK_S` and follows the path tighter
#: (:data:`TIGHT_M` ahead) for :data:`TIGHT_S`
STUCK_M = 0.05
STUCK_S = 2.0
BACK_S = 1.0
TIGHT_M = 0.3
TIGHT_S = 4.0
#: a person who corrected a run may watch it on and take over again where the network leaves the
#: teacher's path again (``record_correction(takeovers=...)``); one correction is one takeover
TAKEOVERS = 1


@dataclass(frozen=True)
class CorrectionPlan:
    """When the person takes over (s of the run), and the teacher's path they drive ``(n, 2)``."""

    take_s: float
    path_xy: np.ndarray
    #: indices into ``path_xy`` where the teacher reached a goal: driven to, not cut short
    stops: tuple[int, ...] = ()


def correction_plan(
    teacher_xy: np.ndarray,
    robot_xy: np.ndarray,
    dt_s: float,
    goals_at: Sequence[int] = (),
    reached_at: Sequence[int] | None = None,
    hit_at: int | None = None,
) -> CorrectionPlan | None:
    """Where the person takes over a run that left the teacher's path or hit a wall, whichever
    came first (None: it did neither); ``goals_at``: the teacher's ticks where it reached a goal,
    in order; ``reached_at``: the robot's ticks where it reached them, in order, as many as it
    reached (None: each in time); ``hit_at``: the robot's tick where it first hit a wall (None:
    it never did). The path near a goal the robot never reached must be met, and a robot that met
    the teacher's path past it missed it there."""
    reached = list(goals_at if reached_at is None else reached_at)
    skip = list(goals_at)[: len(reached)]
    pts = [
        i
        for i in path_points(teacher_xy).tolist()
        if not any(np.hypot(*(teacher_xy[i] - teacher_xy[g])) < GOAL_M for g in skip)
    ]
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(teacher_xy, axis=0).T))])
    stall = round(STALL_S / dt_s)
    t = 0
    last_i, last_t = pts[0], 0
    met: list[tuple[int, int]] = []  # (point, tick) of the points met, in order
    missed = None
    k = 0
    while k < len(pts):
        i = pts[k]
        stretch = teacher_xy[last_i : i + 1]
        away = np.min(np.hypot(*(robot_xy[t:, None, :] - stretch[None, :, :]).transpose(2, 0, 1)), axis=1)
        left = np.nonzero(away > LEAVE_M)[0]
        out = int(left[0]) if len(left) else len(away)
        d = np.hypot(*(robot_xy[t : t + min(out, stall)] - teacher_xy[i]).T)
        hit = np.nonzero(d < RADIUS_M)[0]
        # past a goal it never reached, or meeting the path past a goal it reached only later
        # (coming round again; where the path on runs apart from the way to the goal, not out
        # of a spur beside the way in): missed there, taken over before it
        when = t + int(hit[0]) if len(hit) else None
        late = next(
            (
                n
                for n, g in enumerate(goals_at)
                if arc[i] > arc[g] + LATE_M
                and (
                    n >= len(reached) or (when is not None and reached[n] > when and _apart(teacher_xy, i, g))
                )
            ),
            None,
        )
        if reached_at is not None and late is not None:
            missed = goals_at[late]
            last_i, last_t = max(((a, b) for a, b in met if a <= missed), default=(pts[0], 0))
            break
        if len(hit):
            t += int(hit[0])
            last_i, last_t = i, t
            met.append((i, t))
            k += 1
            continue
        back = (
            _resumed(teacher_xy, robot_xy, pts, k, arc, t + out, stall, round(STRAY_S / dt_s))
            if out < stall
            else None
        )
        if back is None:
            missed = i
            break
        k, t = back
        last_i, last_t = pts[k], t
        k += 1
    if missed is None and reached_at is not None and len(reached) < len(goals_at):
        # it met the whole path, and passed a goal at its end by without its camera reaching it
        missed = goals_at[len(reached)]
        last_i, last_t = max(((a, b) for a, b in met if a <= missed), default=(pts[0], 0))
    lead = round(LEAD_S / dt_s)
    on = None if hit_at is None else _last_on_path(teacher_xy, robot_xy, hit_at)
    if on is not None and (missed is None or on < last_t):
        # it hit a wall before it left the path for good: taken over before the wall, or before
        # it turned off the path where it hit one off it (a dead end it came back out of), and
        # driven past there; the path met before and after (a point is met up to RADIUS_M short)
        lo = ([0, 0] + [a for a, b in met if b <= on])[-2]
        hi = next((a for a, b in met if b > on), len(teacher_xy) - 1)
        last_i = missed = lo + int(np.argmin(np.hypot(*(teacher_xy[lo : hi + 1] - robot_xy[on]).T)))
        take = max(on - lead, 1)
    elif missed is None:
        return None
    else:
        take = max(last_t - lead, 1)
    # the path from the teacher's point nearest where the robot is at the takeover, up to the
    # first point the robot met after it (where the teacher drove in and out of a spur, the way
    # out passes where the robot is too, but the robot has not come to it yet)
    here = robot_xy[take]
    hi = next((a for a, b in met if b > take and a <= last_i), last_i)
    lo = max(hi - 200, 0)
    start = lo + int(np.argmin(np.hypot(*(teacher_xy[lo : hi + 1] - here).T)))
    end = min(int(np.searchsorted(arc, arc[missed] + PAST_M)), len(teacher_xy) - 1)
    return _driving_into_goals(
        teacher_xy, take * dt_s, start, end, [g for g in goals_at if start <= g <= end]
    )


def _last_on_path(teacher_xy: np.ndarray, robot_xy: np.ndarray, hit_at: int) -> int:
    """The robot's last tick up to ``hit_at`` within :data:`RADIUS_M` of the teacher's path (0:
    none): ``hit_at`` where it hit a wall beside the path, where it turned off before one off it."""
    return next(
        (t for t in range(hit_at, -1, -1) if np.min(np.hypot(*(teacher_xy - robot_xy[t]).T)) <= RADIUS_M), 0
    )


def _apart(teacher_xy: np.ndarray, i: int, g: int) -> bool:
    """The teacher's path at ``i`` is :data:`LEAVE_M` from all of its way to ``g`` (before ``i``)."""
    return bool(np.min(np.hypot(*(teacher_xy[: g + 1] - teacher_xy[i]).T)) > LEAVE_M)


def _driving_into_goals(
    teacher_xy: np.ndarray, take_s: float, start: int, end: int, goals: Sequence[int]
) -> CorrectionPlan:
    """The plan driving the teacher's path ``start..end``, where the teacher reached each of
    ``goals`` on :data:`INTO_GOAL_M` the way it was going, and back: the teacher reached a goal at
    the first tick its camera could, at the edge of the camera's reach."""
    pieces: list[np.ndarray] = []
    stops: list[int] = []
    at = start
    for g in sorted(goals):
        way = teacher_xy[g] - teacher_xy[max(g - 5, start)]
        norm = float(np.hypot(*way))
        pieces.append(teacher_xy[at : g + 1])
        if norm > 1e-9:
            pieces.append((teacher_xy[g] + INTO_GOAL_M * way / norm)[None, :])
        stops.append(sum(len(p) for p in pieces) - 1)
        at = g + 1
    pieces.append(teacher_xy[at : end + 1])
    return CorrectionPlan(take_s, np.concatenate(pieces), tuple(stops))


def _resumed(
    teacher_xy: np.ndarray,
    robot_xy: np.ndarray,
    pts: Sequence[int],
    k: int,
    arc: np.ndarray,
    t: int,
    stall: int,
    stray: int,
) -> tuple[int, int] | None:
    """A robot that strayed at tick ``t`` from the path before point ``pts[k]``: where it came back
    to the last point it met, within ``stray`` ticks, and drove on along the path from there
    (``(point index, tick)`` of the first point :data:`RESUME_M` further on, met within ``stall``
    ticks of coming back without straying again), or None (it went elsewhere, or was lost)."""
    last = teacher_xy[pts[k - 1]] if k else teacher_xy[pts[0]]
    near = np.nonzero(np.hypot(*(robot_xy[t:] - last).T) < RADIUS_M)[0]
    if not len(near) or near[0] > stray:
        return None
    t += int(near[0])
    ahead = [j for j in range(k, len(pts)) if arc[pts[j]] >= arc[pts[max(k - 1, 0)]] + RESUME_M]
    if not ahead:
        return None
    j = ahead[0]
    stretch = teacher_xy[pts[max(k - 1, 0)] : pts[j] + 1]
    window = robot_xy[t : t + stall]
    away = np.min(np.hypot(*(window[:, None, :] - stretch[None, :, :]).transpose(2, 0, 1)), axis=1)
    left = np.nonzero(away > LEAVE_M)[0]
    window = window[: int(left[0]) if len(left) else len(window)]
    hit = np.nonzero(np.hypot(*(window - teacher_xy[pts[j]]).T) < RADIUS_M)[0]
    return (j, t + int(hit[0])) if len(hit) else None


class PathPerson:
    """An input source: from ``plan.take_s`` a Twist each period toward the path ``lookahead``
    ahead (pure pursuit on the session's last pose), a hand-back at the path's end; then the
    next of ``then`` (a person who watches on and takes over again), if any."""

    def __init__(self, plan: CorrectionPlan, then: Sequence[CorrectionPlan] = ()) -> None:
        self.plan = plan
        self.then = list(then)
        self.session: TeleopSession | None = None
        self._at = 0
        self.done = False
        self.handed_back_s: float | None = None  # when the last plan was handed back
        self._been: list[tuple[float, float, float]] = []  # (t, x, y) while driving this plan
        self._back_until = self._tight_until = -math.inf

    def poll(self, t_s: float) -> list[Input]:
        if self.done and self.then:
            self.plan, self.then, self._at, self.done = self.then[0], self.then[1:], 0, False
            self._been = []
        if self.done or t_s < self.plan.take_s - 1e-9 or self.session is None:
            return []
        snap = self.session.snapshot
        if snap is None:
            return []
        pose = snap.pose
        path = self.plan.path_xy
        d = np.hypot(path[:, 0] - pose.x, path[:, 1] - pose.y)
        near = self._at + int(np.argmin(d[self._at : self._at + 40]))
        self._at = near
        if near >= len(path) - 3:
            self.done = True
            self.handed_back_s = t_s
            return [Input("handback", "path driven", SOURCE)]
        stop = next((g for g in self.plan.stops if g >= near), None)
        if stop is not None and d[stop] < STOP_M:
            self.plan = replace(self.plan, stops=tuple(g for g in self.plan.stops if g != stop))
            stop = None
        self._been.append((t_s, pose.x, pose.y))
        then = next((b for b in reversed(self._been) if b[0] <= t_s - STUCK_S + 1e-9), None)
        if then is not None and math.hypot(pose.x - then[1], pose.y - then[2]) < STUCK_M:
            self._been = []
            self._back_until, self._tight_until = t_s + BACK_S, t_s + BACK_S + TIGHT_S
        if t_s < self._back_until:
            return [Input("message", twist_payload(-0.5 * SPEED_MPS, 0.0), SOURCE, TWIST_SCHEMA)]
        look = TIGHT_M if t_s < self._tight_until else LOOKAHEAD_M
        ahead = near
        while ahead < len(path) - 1 and d[ahead] < look and ahead != stop:
            ahead += 1
        gx, gy = path[ahead]
        err = math.atan2(gy - pose.y, gx - pose.x) - pose.theta
        err = math.atan2(math.sin(err), math.cos(err))
        v = SPEED_MPS * max(0.0, math.cos(err)) if abs(err) < math.radians(60) else 0.0
        w = max(-1.0, min(1.0, 2.0 * err))
        return [Input("message", twist_payload(v, w), SOURCE, TWIST_SCHEMA)]


def _plan_of(
    log: Path, teacher_xy: np.ndarray, goals_at: Sequence[int], world: World, *, after_s: float = 0.0
) -> CorrectionPlan | None:
    """Where a person takes over the run of ``log`` in ``world`` (:func:`correction_plan`; None: it
    never left the teacher's path nor hit a wall, or the log has no poses); a wall hit before
    ``after_s`` (s of the run: while the person drove) is not the network's."""
    run = read_run(log)
    if run.pose is None:
        return None
    dt_s = float(np.median(np.diff(run.t_ns))) / 1e9
    # the log keeps no collisions: a contact began where a command did not move the robot
    v = run.cmd_v_mps[hold(run.cmd_t_ns, run.t_ns)] if len(run.cmd_t_ns) else np.zeros(len(run))
    hits = [int(h) for h in contacts(run.pose, v, world) if (run.t_ns[h] - run.t_ns[0]) / 1e9 >= after_s]
    achieved = [
        len(lfd.NetworkStep.decode(data).achieved)
        for *_, data in iter_messages(log, topics=[lfd.NetworkStep.TOPIC])
    ]
    reached_at = [
        next(i for i, n in enumerate(achieved) if n >= k) for k in range(1, max(achieved, default=0) + 1)
    ]
    return correction_plan(
        teacher_xy, np.asarray(run.pose[:, :2]), dt_s, goals_at, reached_at, hits[0] if hits else None
    )


def record_correction(
    table: FusionTable,
    *,
    world: World,
    start: Pose,
    seed: int,
    failed_log: Path,
    teacher_xy: np.ndarray,
    max_time_s: float,
    out: Path,
    goals_at: Sequence[int] = (),
    takeovers: int = TAKEOVERS,
) -> Path | None:
    """Correct ``table``'s failed run (its log ``failed_log``, from ``start`` with ``seed``) with a
    :class:`PathPerson`; returns the segmented correction log, or None when the run never left
    the teacher's path (nothing to correct there). With ``takeovers`` > 1 the person watches on
    after handing back: where the network leaves the teacher's path again, they take over there
    too (the run recorded again, tick for tick the same until then), up to ``takeovers`` times."""
    plan = _plan_of(failed_log, teacher_xy, goals_at, world)
    if plan is None:
        return None
    plans = [plan]
    while True:
        opts = TeleopOptions(
            world=world, input_name="script:path-person", seed=seed, start=start, duration_s=max_time_s
        )
        person = PathPerson(plans[0], plans[1:])
        driver = correction_driver(opts, table)
        session = make_session(opts, inputs=[person], clock=SimClock(), network=driver)
        person.session = session
        correct(opts, session=session, driver=driver, table_name="table.yaml", out=out)
        if driver.done or len(plans) >= takeovers or person.handed_back_s is None:
            break
        again = _plan_of(out, teacher_xy, goals_at, world, after_s=person.handed_back_s)
        if again is None or again.take_s <= plans[-1].take_s:
            break  # the network drove on along the path, or left it before the person drove
        # a network that leaves the path right after the hand-back is taken over again at once
        plans.append(replace(again, take_s=max(again.take_s, person.handed_back_s + opts.robot.dt_s)))
    seg = out.with_suffix(".seg.mcap")
    segment_file(out, out=seg, behaviors=",".join(table.behaviors))
    return seg
