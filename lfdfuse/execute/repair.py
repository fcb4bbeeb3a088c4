"""Repair a learned table where its rollouts leave the teacher (:mod:`lfdfuse.execute.check`).

Where the robot leaves the teacher's path, the teacher's turn there is the missing decision, the
next decision's landmark misleads it, the turn just made ended short, or the rows learned after
a goal step's last turn steer it wrong; where it follows the path past a goal it did not reach,
the goal step's rows with the goal in view pull too little toward it. :func:`repair` tries
(:class:`Amends`) such turns as decisions (:func:`lfdfuse.segment.decisions.find_decisions`'s
``forced``), the next decision's other landmark cues (its ``cues``), the teacher's whole turn
(its ``whole``), the goal step's own rows after its last turn
(:func:`lfdfuse.estimate.subgoals.refine`'s ``rest``) and rows learned from the teacher's
approach to the goal (its ``approach``), and keeps one only if the rollouts then follow the
teacher further; when none does, the goal step without its sub-goals (its ``plain``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from lfdfuse.execute.check import Check, DemoWorld, check_all, score
from lfdfuse.network.table import FusionTable
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.decisions import DecisionParams, DecisionPoint
from lfdfuse.segment.track import LandmarkTrack, OpeningCue, teacher_turns

#: a teacher's turn is blamed for a departure when it ended at most this many steps before the
#: last point the robot met
BLAME_STEPS = 30


def blame(track: LandmarkTrack, c: Check, params: DecisionParams) -> int | None:
    """A step of the teacher's turn where the robot left the path: the last turn begun before
    the first point missed that ended near the last point met; failing one, the last such turn
    that left the held heading by ``params.blamed_turn_rad`` only (a corner taken in two)."""
    if c.missed_at is None:
        return None
    for least in (params.min_turn_rad, params.blamed_turn_rad):
        turns = [
            (a, b)
            for a, b, _ in teacher_turns(
                track, 0, len(track.held_rad), began_rad=params.began_rad, min_turn_rad=least
            )
            if a <= c.missed_at and b >= c.last_met_at - BLAME_STEPS
        ]
        if turns:
            return max(turns)[0]
    return None


@dataclass(frozen=True)
class Amends:
    """What a repair changes in how the sub-goals are learned (steps of the demo)."""

    #: the teacher's turns at these steps are decisions (``find_decisions``' ``forced``)
    forced: tuple[int, ...] = ()
    #: the decision at this onset recognises its opening by this cue (its ``cues``)
    cues: tuple[tuple[int, OpeningCue], ...] = ()
    #: the decisions at these onsets turn the teacher's whole turn (its ``whole``)
    whole: tuple[int, ...] = ()
    #: these goal segments end with the goal step's own rows, learned over all of it, not the
    #: rows of what follows the last decision alone
    rest: tuple[int, ...] = ()
    #: these goal segments (without a decision) learn their rows with the goal in view from the
    #: teacher's approach to it (``refine``'s ``approach``)
    approach: tuple[int, ...] = ()
    #: these goal segments drop their decisions: their step is the paper's, learned over all of it
    plain: tuple[int, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.forced or self.cues or self.whole or self.rest or self.approach or self.plain)

    def with_cue(self, onset: int, cue: OpeningCue) -> Amends:
        return replace(self, cues=(*((k, c) for k, c in self.cues if k != onset), (onset, cue)))


@dataclass(frozen=True)
class Repair:
    """The table kept, its decisions, what was amended, and every check made."""

    table: FusionTable
    decisions: tuple[DecisionPoint, ...]
    amends: Amends
    checks: tuple[tuple[Check, ...], ...]  # per table tried, one per start
    kept: tuple[Check, ...]  # the kept table's
    dt_s: float  # the demo's period (steps → seconds)
    goals: int  # the task's goals

    @property
    def changed(self) -> bool:
        return bool(self.amends)

    def describe(self) -> list[str]:
        """What the check found and did, in a few lines."""

        def said(checks: Sequence[Check]) -> str:
            goals, met = score(checks)
            points = sum(c.points for c in checks)
            return f"goals {goals}/{len(checks) * self.goals}, the teacher's path followed {100 * met / max(points, 1):.0f} %"

        first = self.checks[0]
        lines = [f"checked in the demo's world from {len(first)} start(s): {said(first)}"]
        if not self.changed:
            tried = len(self.checks) - 1
            lines.append(
                f"  kept as learned ({tried} repair(s) tried, none followed further)"
                if tried
                else "  kept as learned"
            )
            return lines
        lines.append(f"  repaired ({len(self.checks) - 1} tried): {said(self.kept)}")
        a = self.amends
        lines += [f"  the teacher's turn at {k * self.dt_s:.1f} s is a decision" for k in a.forced]
        lines += [
            f"  the decision met at {k * self.dt_s:.1f} s recognises its opening by {cue}"
            for k, cue in a.cues
        ]
        lines += [
            f"  the decision met at {k * self.dt_s:.1f} s turns the teacher's whole turn" for k in a.whole
        ]
        lines += [
            f"  goal step {k + 1} drives on after its last turn with its own rows, learned over all of it"
            for k in a.rest
        ]
        lines += [
            f"  goal step {k + 1} heads at its goal in view as the teacher approached it" for k in a.approach
        ]
        lines += [f"  goal step {k + 1} has no sub-goals: the paper's step drove further" for k in a.plain]
        return lines


Refine = Callable[[Amends], tuple[FusionTable, Sequence[DecisionPoint]]]


def _heading_for(decisions: Sequence[DecisionPoint], c: Check) -> list[DecisionPoint]:
    """The decision the robot was heading for when it left the path: the first one that ends
    after the last point met."""
    if c.missed_at is None:
        return []
    later = [d for d in decisions if d.turn_end >= c.last_met_at and d.since <= c.missed_at + BLAME_STEPS]
    return later[:1]


def _turned_at(decisions: Sequence[DecisionPoint], c: Check) -> list[DecisionPoint]:
    """The decision whose turn the robot had made when it left the path: the last one that
    began by the last point met and ended before the first one missed."""
    if c.missed_at is None:
        return []
    done = [d for d in decisions if d.onset <= c.last_met_at + BLAME_STEPS and d.turn_end <= c.missed_at]
    return done[-1:]


def _left_in(segments: Sequence[tuple[int, int]], c: Check) -> int | None:
    """The goal segment (index into ``segments``, ``(start, stop)`` steps) the robot left the path in."""
    if c.missed_at is None:
        return None
    return next((k for k, (start, stop) in enumerate(segments) if start <= c.missed_at < stop), None)


def _rest_of(decisions: Sequence[DecisionPoint], segments: Sequence[tuple[int, int]], c: Check) -> list[int]:
    """The goal segment the robot left the path in, when that was after the segment's last decision."""
    k = _left_in(segments, c)
    if k is None or c.missed_at is None:
        return []
    mine = [d for d in decisions if d.segment == k]
    return [k] if mine and mine[-1].turn_end <= c.missed_at else []


def _decided_at(
    decisions: Sequence[DecisionPoint], segments: Sequence[tuple[int, int]], c: Check
) -> list[int]:
    """The goal segment with decisions the robot left the path in."""
    k = _left_in(segments, c)
    return [k] if k is not None and any(d.segment == k for d in decisions) else []


def _approach_of(
    decisions: Sequence[DecisionPoint],
    segments: Sequence[tuple[int, int]],
    goal_segments: Sequence[int],
    c: Check,
) -> list[int]:
    """The goal segment whose goal the robot drove past: the first goal it did not reach, when it
    followed the teacher's path to where the teacher reached it (and the segment has no decision)."""
    if c.goals >= len(goal_segments):
        return []
    k = goal_segments[c.goals]
    if any(d.segment == k for d in decisions):
        return []
    return [k] if c.missed_at is None or c.missed_at >= segments[k][1] - BLAME_STEPS else []


def repair(
    refine: Refine,
    *,
    track: LandmarkTrack,
    home: DemoWorld,
    starts: Sequence[Pose],
    segments: Sequence[tuple[int, int]] = (),
    goal_segments: Sequence[int] = (),
    params: DecisionParams = DecisionParams(),
    rounds: int = 3,
    candidates: int = 4,
) -> Repair:
    """``refine(amends)`` → a table and its decisions. Where a rollout (one per start) leaves the
    teacher's path, try (:class:`Amends`) the teacher's turn there as a decision, the next
    decision's other landmark cues, the teacher's whole turn for the decision just made, and,
    after a goal segment's last decision (``segments``: the demo's goal segments), the goal
    step's own rows; where it followed the path past a goal it did not reach
    (``goal_segments``: the segments ended by the task's goals, in order), that goal step's
    approach rows. Keep the best if the rollouts then follow further, and go on from it. When
    none of those (at most ``candidates``) does, try each goal segment with decisions the robot
    left the path in without them (the paper's step: the sub-goals may be what misleads)."""
    world, teacher_xy, max_time_s = home.world, home.teacher_xy, home.max_time_s
    driven: list[tuple[FusionTable, tuple[Check, ...]]] = []

    def checked(t: FusionTable) -> tuple[Check, ...]:
        """The rollouts of ``t`` from every start; a table driven already (two amends may
        refine to the same table) is not driven again: a rollout is deterministic."""
        got = next((c for u, c in driven if u == t), None)
        if got is None:
            got = check_all(t, world, starts, teacher_xy, max_time_s)
            driven.append((t, got))
        return got

    amends = Amends()
    table, decisions = refine(amends)
    best = checked(table)
    checks = [best]
    for _ in range(rounds):
        cands: list[Amends] = []
        plains: list[Amends] = []
        for c in sorted(best, key=lambda c: c.score):
            step = blame(track, c, params)
            if step is not None and step not in amends.forced:
                cands.append(replace(amends, forced=(*amends.forced, step)))
            for d in _heading_for(decisions, c):
                cands += [amends.with_cue(d.onset, cue) for cue in OpeningCue if cue != d.cue]
            for d in _turned_at(decisions, c):
                if d.onset not in amends.whole:
                    cands.append(replace(amends, whole=(*amends.whole, d.onset)))
            for k in _rest_of(decisions, segments, c):
                if k not in amends.rest:
                    cands.append(replace(amends, rest=(*amends.rest, k)))
            for k in _approach_of(decisions, segments, goal_segments, c):
                if k not in amends.approach:
                    cands.append(replace(amends, approach=(*amends.approach, k)))
            for k in _decided_at(decisions, segments, c):
                plains.append(replace(amends, plain=(*amends.plain, k)))
        found = None
        for tried in (list(dict.fromkeys(cands))[:candidates], list(dict.fromkeys(plains))):
            for a in tried:
                t, ds = refine(a)
                got = checked(t)
                checks.append(got)
                if score(got) > score(best):
                    best, found = got, (a, t, ds)
            if found is not None:
                break
        if found is None:
            break
        amends, table, decisions = found
    return Repair(table, tuple(decisions), amends, tuple(checks), best, home.dt_s, home.goals)
