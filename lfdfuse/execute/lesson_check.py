"""A correction's lesson checked in the demo's world: what the table could do before, it still does.

A correction re-weights the rows of the sub-steps its person drove in, and a row drives the robot
wherever its (step, BAC) comes up, from every start: a few person ticks at the mouth of a dead
end re-weight the drive-on step's rows inside it too, where a robot that strayed in found its way
back out with the demo's rows; the person driving on past a goal re-weights the next goal step's
first sub-step, which the network never failed in. So a start that completed before can fail
after.

Pooled, a row weighs the demo's many steps against the person's few ticks (a row with a thousand
demo steps barely moves for 160 person ticks), so a correction can be taken and change little.
In the goal steps the person took over, the rows the person drove with can be estimated again
with their ticks weighing more (:mod:`lfdfuse.estimate.pooled_rows`): the whole correction read
again so (a :class:`Rereading`) is a lesson of its own.

:func:`checked_lesson` drives the lessons' tables, in order (:data:`ORDER`; each read again only
when reached, and not driven again where it equals one tried or a pooled lesson), from the demo's
check starts (:meth:`~lfdfuse.execute.check.DemoWorld.starts`) and from each correction's own
start (in the demo's world):

``even``
    the whole correction, the person's ticks weighed even with the demo's (its steps thinned
    evenly to as many);
``whole``
    every row and step the correction changed, pooled;
``where taken over``
    rows re-weighted only in the goal steps the person took over in (the network's step at the
    person's first tick); every other row as before, bit for bit;
``steps only``
    the decisions the correction added or re-structured, with their rows; every row of a step
    the table had before as it was;
``person``
    the whole correction, the person's ticks alone;
``corners``
    the correction pooled with its turns read as decisions even where they read as corners
    (:func:`~lfdfuse.estimate.sub_step_corrections.decisions_of`): a spur a few metres past a
    ring's corner reads as one in the correction (the sectors, held at the heading from before
    the corner, see its far wall ahead), so the person's turn into it re-weighted rows only and
    the robot drove past it again. Read so by default, a corner the person cut becomes a
    decision nobody needed (it broke worlds an earlier lesson fixes), so it comes after those.

Last, every lesson tried (in the order tried) with its weights for BACs the table never saw made
safe (``… unseen BACs driven safely``, :func:`~lfdfuse.network.table.safe_defaults`: ``avoid`` at
least at its default weight): a step's default fit leaves ``avoid`` near 0 (the teacher seldom
needed it), and a robot in a BAC its step never saw is most often where the teacher never drove,
near a wall; there it pressed into the wall (a dead end's end wall, a corner) until its time ran
out, whatever the person showed elsewhere. Made safe in every table ``estimate`` writes, the
robot also keeps off the mouths of spurs it should turn into (on 47 of the ``corrections``
bench's worlds, 14 failed from some start against 7), so only where nothing else is taken.

The order is measured on the ``corrections`` bench's failing worlds of seeds 2065–3824 (262),
every lesson's table driven from the check's starts and the bench's. In this order the even
lesson is taken in 129 of them (126 fixed), a pooled one in 73 (68), the person's ticks alone in
8 (8), the turns read at corners in 7 (6), a lesson driven safely in 11 (9), none in 34. Where
several lessons pass the check, which one is taken changes the outcome in few worlds, most often
in a start that completed before failing after (a table marginal where the robot turns off for a
sub-goal, a coin flip on the exact pose that three check starts do not see): with the even
lesson first, 7 of the 262 worlds have such a start and 217 are fixed; with the pooled lessons
first, 12 and 218; with the person's ticks alone first, 11 and 218 (on the 43 failing worlds of
seeds 3825–4104, measured after, the even and the pooled lessons first give the same). The even
table is a table of its own in 7 of 10 worlds (in the others no row of the taken-over steps
holds a row's worth of person ticks). The weighted tables' ``where taken over`` lessons and the
corners reading with the person's ticks alone were never the first to pass, so are not tried
(``steps only`` is the pooled one's: a weighing moves no step).

It takes the first lesson that completes every check start the table before completed and the
corrections' starts; else none (the table before). A lesson that does not carry the robot
through from where the person corrected it has not taught what the person showed, whatever it
does elsewhere: its re-weighted rows only move the robot about by chance, from other starts too.
A start *completes* when the robot reaches every goal without a wall hit, as the benches count
it (a person who takes over before a wall showed a way past it); a check start the table before
drove to every goal with a hit must still reach every goal.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterator, Sequence
from dataclasses import dataclass, replace

from lfdfuse.estimate.pooled_rows import Weighing
from lfdfuse.execute.check import DemoWorld, drive
from lfdfuse.network.table import FusionTable, Network, Step, safe_defaults
from lfdfuse.robot.pose import Pose

#: the lessons tried, largest first (see the module docstring)
LESSONS = ("whole", "where taken over", "steps only")


@dataclass(frozen=True)
class Rereading:
    """How the correction is read into a table again: its ticks' ``weighing`` in the goal steps
    the person took over (:mod:`lfdfuse.estimate.pooled_rows`), and whether its turns are
    decisions even where they read as ``corners``
    (:func:`~lfdfuse.estimate.sub_step_corrections.decisions_of`)."""

    weighing: Weighing = "pool"
    corners: bool = False

    @property
    def name(self) -> str:
        """The whole lesson of the table so read, as :attr:`CheckedLesson.lesson` names it."""
        said = [WEIGHED[self.weighing]] if self.weighing != "pool" else []
        if self.corners:
            said.append(
                "their turns read at corners too" if said else "the person's turns read at corners too"
            )
        return ", ".join(["whole", *said])


#: how each weighing is named in the lesson taken
WEIGHED: dict[Weighing, str] = {
    "even": "the person's ticks weighed even with the demo's",
    "person": "the person's ticks alone",
}
#: how a lesson with its weights for unseen BACs made safe is named (the last lessons tried)
SAFE = "unseen BACs driven safely"
#: the lessons in the order tried (see the module docstring): a pooled lesson by its name
#: (:data:`LESSONS`), the whole lesson of the correction read again by its :class:`Rereading`
ORDER: tuple[str | Rereading, ...] = (
    Rereading("even"),
    "whole",
    "where taken over",
    "steps only",
    Rereading("person"),
    Rereading("pool", corners=True),
)
#: the readings of the correction again, in the order tried
LADDER: tuple[Rereading, ...] = tuple(r for r in ORDER if isinstance(r, Rereading))


@dataclass(frozen=True)
class CheckedLesson:
    """The table taken, which lesson it is (None: none, the table before) and why."""

    table: FusionTable
    lesson: str | None
    why: str
    #: the reading of the correction the table taken was made from (None: the pooled one)
    reading: Rereading | None = None

    def describe(self) -> str:
        took = "the table before (the correction not taken)" if self.lesson is None else self.lesson
        return f"lesson checked in the demo's world: {took}: {self.why}"


def _leaves(net: Network, prefix: str = "") -> dict[str, Step]:
    out: dict[str, Step] = {}
    for st in net.steps:
        name = f"{prefix}{st.name}"
        if st.network is not None:
            out.update(_leaves(st.network, name + "/"))
        else:
            out[name] = st
    return out


def _rows_back(table: FusionTable, before: FusionTable, keep: Callable[[str], bool]) -> FusionTable:
    """``table`` with every leaf ``before`` also has (by its nested name) back to ``before``'s rows,
    but those ``keep`` names."""
    old = _leaves(before.network)

    def walk(net: Network, prefix: str) -> Network:
        steps = []
        for st in net.steps:
            name = f"{prefix}{st.name}"
            if st.network is not None:
                steps.append(replace(st, network=walk(st.network, name + "/")))
                continue
            o = old.get(name)
            if o is not None and not keep(name) and o.fusion != st.fusion:
                st = replace(st, fusion=o.fusion)
            steps.append(st)
        return replace(net, steps=tuple(steps))

    return replace(table, network=walk(table.network, ""))


def lessons(
    before: FusionTable, whole: FusionTable, taken_over: Collection[str]
) -> list[tuple[str, FusionTable]]:
    """The tables of :data:`LESSONS`, each that changes a row or step of ``before`` and differs
    from those before it: ``taken_over`` the goal steps (top-level names) the person took over in."""
    made = [
        ("whole", whole),
        ("where taken over", _rows_back(whole, before, lambda n: n.split("/", 1)[0] in taken_over)),
        ("steps only", _rows_back(whole, before, lambda n: False)),
    ]
    out: list[tuple[str, FusionTable]] = []
    for name, table in made:
        if table.network != before.network and all(table.network != t.network for _, t in out):
            out.append((name, table))
    return out


def checked_lesson(
    before: FusionTable,
    whole: FusionTable,
    *,
    taken_over: Collection[str],
    home: DemoWorld,
    starts: Sequence[Pose],
    corrections: Sequence[Pose],
    reread: Callable[[Rereading], FusionTable] | None = None,
) -> CheckedLesson:
    """The first lesson (in :data:`ORDER`: the pooled lessons of ``whole`` and the tables
    ``reread`` makes, the correction's table with the correction read so) that keeps what
    ``before`` completed from ``starts`` in ``home`` and completes from the ``corrections``'
    starts (see the module docstring)."""
    tried = lessons(before, whole, taken_over)
    if not tried:
        return CheckedLesson(whole, "whole", "no row or step changed")
    everywhere = [*starts, *corrections]

    def outcomes(table: FusionTable, at: Sequence[Pose]) -> list[tuple[bool, bool]]:
        """Per start: every goal reached, and that without a wall hit (completed)."""
        out = []
        for s in at:
            d = drive(table, home.world, s, home.max_time_s)
            out.append((d.goals >= home.goals, d.goals >= home.goals and d.collisions == 0))
        return out

    base = outcomes(before, starts)
    kept_starts = False
    for name, table, reading in _ladder(before, tried, reread):
        done = outcomes(table, everywhere)
        if not all(d[k] for d, b in zip(done, base, strict=False) for k in (0, 1) if b[k]):
            continue
        if all(d[1] for d in done[len(starts) :]):
            return CheckedLesson(
                table,
                name,
                f"{_count([d[1] for d in done[: len(starts)]], [b[1] for b in base])}; the correction's start completes",
                reading,
            )
        kept_starts = True
    if kept_starts:
        return CheckedLesson(before, None, "no lesson completes the correction's start: correct it again")
    return CheckedLesson(before, None, "every lesson fails a check start the table before completed")


def _ladder(
    before: FusionTable,
    pooled: list[tuple[str, FusionTable]],
    reread: Callable[[Rereading], FusionTable] | None,
) -> Iterator[tuple[str, FusionTable, Rereading | None]]:
    """The lessons in the order tried (:data:`ORDER`), each with the reading it was made from
    (None: the pooled one): the ``pooled`` lessons and the whole lessons of the correction read
    again, each of those made when reached; a table tried before is not tried again, nor one a
    pooled lesson is (the reading moved no row or step of it: it is tried under the pooled
    lesson's name); then each of those with its unseen BACs driven safely, where that changes it."""
    tables = dict(pooled)  # distinct, and each changes ``before`` (:func:`lessons`)
    tried: list[tuple[str, FusionTable, Rereading | None]] = []
    seen = [before.network, *(t.network for t in tables.values())]
    for lesson in ORDER:
        if isinstance(lesson, str):
            if lesson in tables:
                tried.append((lesson, tables[lesson], None))
                yield tried[-1]
            continue
        if reread is None:
            continue
        table = reread(lesson)
        if table.network in seen:
            continue
        seen.append(table.network)
        tried.append((lesson.name, table, lesson))
        yield tried[-1]
    made: list[FusionTable] = []
    for name, table, read_so in tried:
        safe = safe_defaults(table)
        if safe == table or safe in made:
            continue
        made.append(safe)
        yield f"{name}, {SAFE}", safe, read_so


def _count(done: Sequence[bool], base: Sequence[bool]) -> str:
    return f"{sum(done)} of {len(done)} check starts complete ({sum(base)} before)"
