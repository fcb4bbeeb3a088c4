"""How results look in the terminal: runs, segments, fusion tables, execute reports."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rich.table import Table

from lfdfuse.behaviors.names import abbreviation, legend_entry
from lfdfuse.cli.common import console
from lfdfuse.cli.tables import show
from lfdfuse.execute.report import help_line, verdict
from lfdfuse.network.table import FusionRow, FusionTable, Network
from lfdfuse.segment.goals import Segmentation, bac_summary
from lfdfuse.sim.loop import RunSummary
from lfdfuse.words import counted


def print_run(summary: RunSummary, *, title: str) -> None:
    console.print(f"[bold]{title}[/bold] → {summary.out}")
    console.print(f"  duration   {summary.duration_s:8.1f} s   ({summary.steps} steps)")
    console.print(f"  distance   {summary.distance_m:8.1f} m")
    console.print(f"  collisions {summary.collisions:8d}")
    reached = ", ".join(f"{n} at {t:.1f} s" for n, t in summary.reached) or "none"
    console.print(f"  targets    {reached}")
    console.print(
        f"  side range left {summary.left_range_mean_m:.2f} m, right {summary.right_range_mean_m:.2f} m (mean at ±90°)"
    )


def print_segments(segm: Segmentation, names: tuple[str, ...], t_ns: Sequence[int]) -> None:
    """Each goal segment: its goal, how long it lasted (from its first step to the next segment's,
    or to the demo's last step: the durations add up to the demo's), its steps and BACs."""
    for seg in segm.segments:
        bacs = bac_summary(segm, seg)
        goal = seg.goal or "no goal reached"
        steps = seg.stop - seg.start
        last = min(seg.stop, len(t_ns) - 1)
        secs = (int(t_ns[last]) - int(t_ns[seg.start])) / 1e9
        console.print(
            f"  [bold]segment {seg.index}[/bold] → {goal}: {secs:.1f} s, {counted(steps, 'step')},"
            f" {counted(len(bacs), 'BAC')}"
        )
        cells = [f"{b}={bac_names(b, names)} ({n})" for b, n, _ in bacs]
        console.print("    BAC (samples): " + ", ".join(cells))


def bac_names(bac: int, names: tuple[str, ...] | list[str]) -> str:
    """A BAC in words: the abbreviations of its applicable behaviours (bit i ⇔ ``names[i]``), ``+``-joined."""
    on = [abbreviation(n) for i, n in enumerate(names) if int(bac) >> i & 1]
    return "+".join(on) or "none"


def print_provenance(table: FusionTable) -> None:
    """Which method made a table, from what, with which settings (its ``estimated_by``)."""
    by = dict(table.estimated_by)
    if not by:
        console.print("  made by: not recorded (a hand-written table?)")
        return
    head = [str(by.pop(k)) for k in ("method",) if k in by]
    trials = by.pop("trials", None)
    if trials is not None:
        head.append(f"{trials} trial{'s' if int(trials) != 1 else ''}")
    if "seed" in by:
        head.append(f"seed {by.pop('seed')}")
    source = by.pop("source", None)
    rest = ", ".join(f"{k} {v}" for k, v in by.items())
    console.print(
        f"  made by: {', '.join(head)}"
        + (f", from {source}" if source else "")
        + (f" ({rest})" if rest else "")
    )


def print_table(table: FusionTable) -> None:
    """Weights (± std), samples and fit error per step and BAC, in percent to fit a terminal."""
    from lfdfuse.estimate.methods import EstimateOptions, is_point_fit  # the fit's stack: only here

    legend = ", ".join(legend_entry(b) for b in table.behaviors)
    by = table.estimated_by
    # a least-squares fit has no uncertainty: its std is 0 by construction unless bootstrapped
    show_std = not (is_point_fit(by.get("method")) and int(by.get("trials", 1)) == 1)
    spread = (
        "weights ± std in % of the row"
        if show_std
        else f"weights in % of the row ({by.get('method')} has no uncertainty: --trials K bootstraps one)"
    )
    # a least-squares fit has no prior: where the data cannot tell weights apart, it picks one fit
    undecided = "one of many equal fits" if is_point_fit(by.get("method")) else "the prior decides"
    console.print(
        "BAC = the set of applicable behaviours (bit i = the i-th below; a blank weight: not applicable); "
        f"{spread}; n = samples (* = too few to trust); fit° = mean heading error;"
        f" BAC? = not identifiable ({undecided})\n{legend}"
    )

    def walk(net: Network, depth: int) -> None:
        for step in net.steps:
            goal = f"goal {step.goal}" if step.goal else "no goal"
            if step.landmark is not None:  # a sub-goal at a decision point
                goal = f"sub-goal: until {step.landmark.describe()}"
            console.print(f"{'  ' * depth}[bold]{step.name}[/bold] ({goal})")
            if step.network is not None:
                walk(step.network, depth + 1)
                continue
            t = Table(box=None, header_style="bold", pad_edge=False, padding=(0, 1))
            t.add_column("BAC", justify="right")
            t.add_column("n", justify="right")
            t.add_column("fit°", justify="right")
            for b in table.behaviors:
                t.add_column(abbreviation(b), justify="right")
            for row in sorted(step.fusion, key=lambda r: -(r.samples or 0)):
                cells = []
                for b in table.behaviors:
                    if b in row.weights:
                        sd = (row.std or {}).get(b) if show_std else None
                        cells.append(
                            f"{100 * row.weights[b]:.0f}" + (f"±{100 * sd:.0f}" if sd is not None else "")
                        )
                    else:
                        cells.append("")
                n = f"{row.samples}" + ("*" if row.low_samples else "") if row.samples is not None else ""
                fit = f"{row.fit_error_deg:.1f}" if row.fit_error_deg is not None else ""
                t.add_row(f"{row.bac}{'?' if row.identifiable is False else ''}", n, fit, *cells)
            if step.fusion:
                show(t)
            else:
                console.print("    (no informative steps: default weights)")

    walk(table.network, 0)
    few = [r for r in _rows(table.network) if r.low_samples]
    point = is_point_fit(table.estimated_by.get("method"))
    little = "a fit to so few says little" if point else "their weights say little more than the prior"
    if few:
        least = min(r.samples or 0 for r in few)
        console.print(
            f"[bold]{len(few)} of {len(_rows(table.network))} row(s) learned from too few samples[/bold] (n*,"
            f" fewer than {EstimateOptions().min_samples}; the least {least}): {little};"
            " demonstrate those situations longer"
        )


def _rows(net: Network) -> list[FusionRow]:
    """Every fusion row of a network, nested steps included."""
    out: list[FusionRow] = []
    for step in net.steps:
        out += _rows(step.network) if step.network is not None else list(step.fusion)
    return out


def changed_rows(table: FusionTable) -> list[tuple[str, FusionRow]]:
    """The rows pooled demos changed (``samples_added``), with their step's name, in table order."""
    out: list[tuple[str, FusionRow]] = []

    def walk(net: Network) -> None:
        for step in net.steps:
            if step.network is not None:
                walk(step.network)
            out.extend((step.name, r) for r in step.fusion if r.samples_added)

    walk(table.network)
    return out


def print_changes(table: FusionTable) -> None:
    """Per row the later demos changed: the samples they added and the weights before → after."""
    sources = table.estimated_by.get("sources")
    rows = changed_rows(table)
    if not isinstance(sources, list) or len(sources) < 2:
        return
    modes = table.estimated_by.get("source_commands")
    named = [str(s) for s in sources]
    if isinstance(modes, list) and len(modes) == len(sources):  # each read by its own command model
        named = [f"{s} {m}" for s, m in zip(named, modes, strict=True)]
    console.print(
        f"pooled {len(sources)} demos ({', '.join(named)}): {len(rows)} row(s) changed "
        f"by the demos after {sources[0]}; every other row is {sources[0]}'s alone"
    )
    for name, r in rows:
        before = r.weights_before or {}
        moves = ", ".join(
            f"{abbreviation(b)} {100 * before[b]:.0f}→{100 * w:.0f}"
            if b in before
            else f"{abbreviation(b)} {100 * w:.0f}"
            for b, w in r.weights.items()
        )
        what = "new row" if r.weights_before is None else "weights %"
        console.print(
            f"  {name} BAC {r.bac} ({bac_names(r.bac, table.behaviors)}): +{counted(r.samples_added or 0, 'sample')} "
            f"({r.samples} in all), {what}: {moves}"
        )


def print_subgoals(table: FusionTable) -> None:
    """Explain the sub-goals at decision points: where the network turns off its route."""
    for step in table.network.steps:
        inner = step.network
        if inner is None or not any(s.landmark is not None for s in inner.steps):
            continue
        parts = []
        for s in inner.steps:
            lm = s.landmark
            if lm is None:
                parts.append(f"reach {s.goal}" if s.goal else s.name)
            elif lm.kind == "opening":
                parts.append(f"drive on to {lm.describe()}")
            else:
                parts.append(f"turn into it ({lm.describe()})")
        console.print(f"  [bold]{step.name}[/bold]: " + ", then ".join(parts))
    console.print(
        "  (sub-goals mark where the teacher turned off toward a goal still out of view; openings are"
        " counted from the robot's own scan since the step began, turns from its odometry)"
    )


def print_report(rep: dict[str, Any], *, out: str) -> None:
    if rep["completed"] is None:
        status = "a network without goals (nothing to complete) ran"
    else:
        status = "task completed" if rep["completed"] else "task not completed"
    console.print(
        f"[bold]execute[/bold] → {out}: {status} in {rep['duration_s']:.1f} s, {rep['path_length_m']:.1f} m, {counted(rep['collisions'], 'collision')}"
    )
    for g in rep["goals"]:
        when = f"at {g['time_s']:.1f} s" if g["reached"] else "not reached"
        console.print(f"  goal {g['name']} ({g['target']}): {when}")
    for s in rep["steps"]:
        console.print(
            f"  step {s['name']}: side range left {s['left_range_mean_m']:.2f} m, right {s['right_range_mean_m']:.2f} m"
        )
    console.print(
        f"  overall: left {rep['left_range_mean_m']:.2f} m, right {rep['right_range_mean_m']:.2f} m; default weights on {100 * rep['unseen_bac_fraction']:.1f}% of ticks"
    )
    asked = help_line(rep)
    if asked is not None:
        console.print(f"  {asked}", markup=False)
    console.print(f"  [bold]verdict[/bold]: {verdict(rep)}")
