"""Learning from demonstration, written out once: demo(s) → fusion table, and teacher → demo.

:func:`learn` is the one path from segmented demonstrations to a :class:`FusionTable` that
``lfdfuse estimate``, the paper's experiments, the benches, the round trips and the tests call:
several demos are pooled into one table (:func:`lfdfuse.estimate.pipeline.estimate_runs`); each
demo is read in one pass over its messages (its ``/lfd/*`` channels, and with sub-goals its
``/scan`` and ``/pose`` too: :func:`lfdfuse.segment.read.read_segmented_and_run`),
estimated once (:func:`lfdfuse.estimate.pipeline.estimate_run`), and with ``subgoals`` the table
is refined at the demo's decision points (:func:`lfdfuse.estimate.subgoals.refine`), which
estimates only the new sub-segment rows. :func:`learn_run` is the same on a run in memory.

:func:`demonstrate` is the other half: a teacher (a task's legs, or a fusion table driving the
network teacher) demonstrates in a world, and the demo is segmented.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.demo_alignment import same_behaviors
from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run, estimate_runs
from lfdfuse.estimate.pooled_subgoals import PooledSubgoals, Verdict, pool_subgoals
from lfdfuse.estimate.sub_step_corrections import FurtherDemo, taken_over
from lfdfuse.estimate.subgoals import refine, track_of
from lfdfuse.execute.check import CHECK_STARTS, DemoWorld, demo_world
from lfdfuse.execute.lesson_check import CheckedLesson, Rereading, checked_lesson
from lfdfuse.execute.repair import Amends, Repair, repair
from lfdfuse.execute.run import ExecuteOptions, run_table
from lfdfuse.log.reader import Run
from lfdfuse.network.changes import step_changes
from lfdfuse.network.table import FusionTable, leaf_steps
from lfdfuse.progress import Progress, part, tell
from lfdfuse.robot.pose import Pose
from lfdfuse.segment.decisions import DecisionParams, DecisionPoint
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import (
    SegmentedRun,
    network_steps,
    person_ticks,
    read_segmented,
    read_segmented_and_run,
)
from lfdfuse.segment.track import LandmarkTrack
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.parse import World

#: a segmented correction log (``teleop --table``) says how many ticks its network drove
CORRECTION_KEY = "segment_network_ticks"


@dataclass(frozen=True)
class LearnOptions:
    """How demos are learned: the estimator, and whether decision points become sub-goals."""

    estimate: EstimateOptions = field(default_factory=EstimateOptions)
    subgoals: bool = False
    decisions: DecisionParams = field(default_factory=DecisionParams)  # subgoals: what a decision is
    #: subgoals, a demo with its world: drive the table there from the teacher's start and this
    #: many perturbed starts, and repair it where it leaves the teacher's path
    #: (:mod:`lfdfuse.execute.check`); None: no check
    check_starts: int | None = CHECK_STARTS


@dataclass(frozen=True)
class LearnResult:
    """The learned table and what learning measured."""

    table: FusionTable
    groups: int  # (goal segment, BAC) groups of the demo
    skipped: int  # groups with no informative step (their BAC falls back to the default weights)
    decisions: tuple[DecisionPoint, ...] = ()  # subgoals: the decision points found
    sources: tuple[str, ...] = ()  # the demos, by name
    repair: Repair | None = None  # subgoals checked in the demo's world: what the check did
    #: subgoals over several demos: what became of each decision (kept, merged, dropped, added)
    verdicts: tuple[Verdict, ...] = ()
    #: a correction pooled with sub-goals: the lesson checked in the demo's world
    #: (:mod:`lfdfuse.execute.lesson_check`)
    lesson: CheckedLesson | None = None


def learn_run(
    run: SegmentedRun,
    *,
    options: LearnOptions = LearnOptions(),
    track: LandmarkTrack | None = None,
    name: str = "demo",
    progress: Progress | None = None,
    home: DemoWorld | None = None,
) -> LearnResult:
    """The table of a segmented run in memory; ``track`` (its landmark cues) is needed for sub-goals,
    ``home`` (where it was driven) for their check.

    ``progress`` is told how far learning is, many times over a long estimate. With sub-goals
    the first pass is the first half: the refinement estimates the decided segments again, at
    most as much work again (where the decisions are is known only after the first pass).
    """
    if options.subgoals and track is None:
        raise ConfigError("sub-goals need the demo's landmark track (its /scan and /pose)")
    share = 0.5 if options.subgoals else 1.0
    first = part(progress, start=0.0, size=share, total=1.0)
    table, groups, skipped = estimate_run(run, opts=options.estimate, name=name, progress=first)
    decisions: tuple[DecisionPoint, ...] = ()
    fixed: Repair | None = None
    if options.subgoals and track is not None:
        then = part(progress, start=share, size=1.0 - share, total=1.0)
        table, decisions, fixed = _with_subgoals(table, run, track, home, options, then)
    return LearnResult(table, groups, skipped, decisions, (name,), fixed)


def _with_subgoals(
    table: FusionTable,
    run: SegmentedRun,
    track: LandmarkTrack,
    home: DemoWorld | None,
    options: LearnOptions,
    progress: Progress | None,
) -> tuple[FusionTable, tuple[DecisionPoint, ...], Repair | None]:
    """``table`` (the paper's of ``run``) refined at the run's decision points, checked in its
    world ``home`` when it has one; with the decisions kept and what the check did."""
    if home is not None and options.check_starts is not None:
        fixed = subgoals_checked(table, run, track, home, options, progress=progress)
        return fixed.table, fixed.decisions, fixed
    res = refine(table, run, track, opts=options.estimate, params=options.decisions, progress=progress)
    return res.table, res.decisions, None


def home_of(raw: Run, run: SegmentedRun) -> DemoWorld | None:
    """Where the demo ``raw`` (segmented as ``run``) was driven, to check its sub-goals in
    (:func:`lfdfuse.execute.check.demo_world`: only a demo lfdfuse drove has one)."""
    return demo_world(raw, goals=sum(seg.goal is not None for seg in run.segments))


def subgoals_checked(
    table: FusionTable,
    run: SegmentedRun,
    track: LandmarkTrack,
    home: DemoWorld,
    options: LearnOptions,
    *,
    progress: Progress | None = None,
) -> Repair:
    """``table`` (the paper's table of ``run``) with sub-goals, checked in the demo's world and
    repaired where the robot leaves the teacher's path (:func:`lfdfuse.execute.repair.repair`)."""

    def refined(amends: Amends) -> tuple[FusionTable, Sequence[DecisionPoint]]:
        res = refine(
            table,
            run,
            track,
            opts=options.estimate,
            params=options.decisions,
            forced=amends.forced,
            cues=dict(amends.cues),
            whole=amends.whole,
            rest=amends.rest,
            approach=amends.approach,
            plain=amends.plain,
            progress=progress,
        )
        return res.table, res.decisions

    return repair(
        refined,
        track=track,
        home=home,
        starts=home.starts(options.check_starts or 0, options.estimate.seed),
        segments=tuple((s.start, s.stop) for s in run.segments),
        goal_segments=tuple(s.index for s in run.segments if s.goal is not None),
        params=options.decisions,
    )


def learn(
    demos: Sequence[str | Path],
    *,
    options: LearnOptions = LearnOptions(),
    progress: Progress | None = None,
) -> LearnResult:
    """The fusion table of segmented demo logs, pooled (:mod:`lfdfuse.estimate.demo_alignment`): a row's
    likelihood is the product over the demos that met its (step, BAC); each demo keeps its own
    lag (its segmentation's). A correction log (``teleop --table``, segmented) is one more demo
    whose network-driven ticks are non-informative, so only the person's ticks change rows."""
    if not demos:
        raise ConfigError("learning needs at least one demonstration")
    if len(demos) == 1:
        src = demos[0]
        name = Path(src).name
        track: LandmarkTrack | None = None
        home: DemoWorld | None = None
        if options.subgoals:
            run, raw = read_segmented_and_run(src)
            track = track_of(raw, run, source=str(src))
            home = home_of(raw, run)
        else:
            run = read_segmented(src)
        return learn_run(run, options=options, track=track, name=name, progress=progress, home=home)
    where = [Path(d).resolve() for d in demos]
    if len(set(where)) != len(where):
        raise ConfigError("the same demonstration is given twice: its evidence would count double")
    names = [Path(d).name for d in demos]
    if len(set(names)) != len(names):
        names = [str(d) for d in demos]
    if options.subgoals:
        return _learn_subgoals_pooled(demos, names, options, progress)
    runs = [read_segmented(d) for d in demos]
    table, groups, skipped = estimate_runs(runs, opts=options.estimate, names=names, progress=progress)
    return LearnResult(table, groups, skipped, (), tuple(names))


def _learn_subgoals_pooled(
    demos: Sequence[str | Path], names: Sequence[str], options: LearnOptions, progress: Progress | None
) -> LearnResult:
    """Sub-goals from several demos (:mod:`lfdfuse.estimate.pooled_subgoals`): the first demo
    learned (and checked) as alone, the others' decisions matched to its, their rows pooled; with
    a correction, the lesson checked in the demo's world (:mod:`lfdfuse.execute.lesson_check`: the
    correction read again — its ticks weighed even with the demo's first, alone or its turns read
    at corners too after the pooled lessons — each estimated only when reached, then each lesson
    with its unseen BACs driven safely; the verdicts and decisions are the table's taken)."""
    read = [read_segmented_and_run(d) for d in demos]
    runs = [run for run, _ in read]
    why = same_behaviors(runs, names)
    if why is not None:
        raise ConfigError(why)
    run, raw = read[0]
    if CORRECTION_KEY in run.metadata:
        raise ConfigError(
            f"{names[0]} is a correction (teleop --table): with --subgoals give the teacher's demo first"
        )
    track = track_of(raw, run, source=str(demos[0]))
    first = part(progress, start=0.0, size=0.4, total=1.0)
    paper, groups, skipped = estimate_run(run, opts=options.estimate, name=names[0], progress=first)
    then = part(progress, start=0.4, size=0.4, total=1.0)
    home = home_of(raw, run)
    table, decisions, fixed = _with_subgoals(paper, run, track, home, options, then)
    others = [
        FurtherDemo(
            name,
            r,
            track_of(w, r, source=str(src)),
            CORRECTION_KEY in r.metadata,
            network_steps(src, r.t_ns) if CORRECTION_KEY in r.metadata else None,
            person_ticks(src, r.t_ns) if CORRECTION_KEY in r.metadata else None,
        )
        for name, src, (r, w) in zip(names[1:], demos[1:], read[1:], strict=True)
    ]

    def pooled(reading: Rereading = Rereading()) -> PooledSubgoals:
        return pool_subgoals(
            first=run,
            first_name=names[0],
            paper=paper,
            table=table,
            decisions=decisions,
            others=others,
            opts=options.estimate,
            params=options.decisions,
            weighing=reading.weighing,
            corners=reading.corners,
        )

    res = pooled()
    built, checked = res.table, None
    made: dict[Rereading, PooledSubgoals] = {}  # the correction read again, as made

    def reread(reading: Rereading) -> FusionTable:
        made[reading] = pooled(reading)
        return made[reading].table

    if home is not None and options.check_starts is not None and any(o.correction for o in others):
        checked = checked_lesson(
            table,
            res.table,
            taken_over=taken_over(others),
            home=home,
            starts=home.starts(options.check_starts, options.estimate.seed),
            corrections=[
                Pose(*(float(v) for v in w.pose[0]))
                for o, (_, w) in zip(others, read[1:], strict=True)
                if o.correction and w.pose is not None and len(w.pose) and w.world_yaml == raw.world_yaml
            ],
            reread=reread,
        )
        built = checked.table
        # a table read again taken (or made safe): its verdicts (with the turns read at corners,
        # its decisions)
        if checked.reading is not None:
            res = made[checked.reading]
    tell(progress, 1.0, 1.0)
    return LearnResult(built, groups, skipped, res.decisions, tuple(names), fixed, res.verdicts, checked)


@dataclass(frozen=True)
class Lesson:
    """What a correction teaches: the table estimated again with it, and in words what changed."""

    table: FusionTable
    changes: tuple[str, ...]  # one line per goal step added, re-structured or re-weighted
    verdicts: tuple[Verdict, ...]  # with sub-goals: what became of each decision
    segmented: Path  # the correction, segmented with the table's behaviours
    checked: CheckedLesson | None = None  # with sub-goals: the lesson checked in the demo's world


def correction_lesson(
    table: FusionTable,
    *,
    demos: Sequence[str | Path],
    correction: str | Path,
    folder: Path,
    options: LearnOptions = LearnOptions(),
    progress: Progress | None = None,
) -> Lesson:
    """``table`` (learned from ``demos``) estimated again with the ``correction`` log recorded
    against it (``teleop --table``): the log is segmented into ``folder`` with the table's
    behaviours, and learned with the demos — with sub-goals when the table has landmark steps."""
    seg = folder / f"{Path(correction).name.removesuffix('.mcap')}.seg.mcap"
    segment_file(correction, out=seg, behaviors=",".join(table.behaviors))
    subgoals = any(s.landmark is not None for s in leaf_steps(table))
    res = learn([*demos, seg], options=replace(options, subgoals=subgoals), progress=progress)
    return Lesson(res.table, tuple(step_changes(table, res.table)), res.verdicts, seg, res.lesson)


# ------------------------------------------------------------------------------ demonstrate


@dataclass(frozen=True)
class Demonstration:
    """A demonstration on disk: the raw log, the segmented one, how long it ran."""

    raw: Path
    segmented: Path
    steps: int  # simulation steps
    duration_s: float  # simulated time
    wall_s: float  # wall time to drive it (segmenting not counted)


def demonstrate(
    teacher: Sequence[Leg] | FusionTable,
    *,
    world: World,
    folder: Path,
    name: str,
    duration_s: float,
    seed: int,
    teacher_name: str = "task",
    heading_noise_rad: float = 0.0,
    start: tuple[float, float, float] | None = None,
    behaviors: str | None = None,
    measure_lag: bool = True,
    keys_period_s: float | None = None,
) -> Demonstration:
    """Demonstrate in ``world`` and segment: ``folder/name.mcap`` and ``folder/name.seg.mcap``
    (``folder`` is created).

    ``teacher`` is a task's legs (the scripted style teacher, ``simulate --teacher``, named
    ``teacher_name`` in the log) or a fusion table (the network teacher, ``simulate --teacher
    TABLE``, with ``heading_noise_rad``); ``keys_period_s`` makes a task's teacher a person at a
    keyboard (``simulate --keys``). ``behaviors`` (default: the segment preset, or the table's
    behaviours) and ``measure_lag`` are ``segment``'s.
    """
    folder.mkdir(parents=True, exist_ok=True)
    raw, seg = folder / f"{name}.mcap", folder / f"{name}.seg.mcap"
    pose = None if start is None else Pose(*start)
    t0 = time.perf_counter()
    if isinstance(teacher, FusionTable):
        opts = ExecuteOptions(
            world=world,
            table=teacher,
            start=pose,
            max_time_s=duration_s,
            seed=seed,
            heading_noise_rad=heading_noise_rad,
        )
        summary = run_table(opts, out=raw, command="simulate", teacher=True).summary
        behaviors = behaviors or ",".join(teacher.behaviors)
    else:
        summary = simulate(
            SimulateOptions(
                world=world,
                legs=list(teacher),
                teacher_name=teacher_name,
                duration_s=duration_s,
                seed=seed,
                start=pose,
                keys_period_s=keys_period_s,
            ),
            out=raw,
        )
    wall = time.perf_counter() - t0
    if behaviors is None:
        segment_file(raw, out=seg, measure_lag=measure_lag)
    else:
        segment_file(raw, out=seg, behaviors=behaviors, measure_lag=measure_lag)
    return Demonstration(raw, seg, summary.steps, summary.duration_s, wall)
