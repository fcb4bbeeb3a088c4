"""The comparison table of the report: the paper's result beside ours, measured in this run.

The paper's side is quoted from its text (section and figure cited); where the paper gives a
number only inside a figure we do not invent one and compare the claim instead. ``agrees`` is
True or False when the claim can be checked on our numbers, None where it cannot (a different
building, robot or demonstrator makes the count itself incomparable).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from lfdfuse.evaluate.paper.experiments import step_of_ticks
from lfdfuse.evaluate.paper.records import Learned, PaperResults, PaperRun, passing_sides, task_order
from lfdfuse.execute.starts import wilson_interval
from lfdfuse.network.table import FusionTable, table_steps
from lfdfuse.segment.read import read_segmented
from lfdfuse.world.model import load_world

SIDE = {"keep-left": "left", "keep-center": "centre", "keep-right": "right"}


@dataclass(frozen=True)
class Row:
    experiment: str
    source: str  # where in the paper
    paper: str
    ours: str
    agrees: bool | None
    note: str = ""

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _lr(run: PaperRun) -> str:
    """The number a run's style is judged by (:func:`~lfdfuse.execute.report.corridor_style`): its
    median offset from the corridor's centre where both walls are within 2 m."""
    both = (run.left_m < 2.0) & (run.right_m < 2.0)
    if not both.any():
        return "never both walls within 2 m"
    offset = float(np.median(run.right_m[both] - run.left_m[both])) / 2
    side = "left" if offset > 0 else "right"
    return f"median {abs(offset):.2f} m {side} of centre where both walls are within 2 m; ≤ 0.25 m is centre"


def _count(runs: Sequence[PaperRun], style: str) -> int:
    return sum(r.style == style and r.report["collisions"] == 0 for r in runs)


def task_ok(run: PaperRun) -> bool:
    rep = run.report
    return bool(rep["completed"]) and task_order(rep) == ["red", "green", "blue"] and rep["collisions"] == 0


def task_steps_kept(runs: Sequence[PaperRun]) -> tuple[int, int]:
    """(steps whose style matched the demonstrated one, steps judged) over the completed runs."""
    want = {"reach-red": "left", "reach-green": "centre", "reach-blue": "right"}
    good = total = 0
    for run in runs:
        if not task_ok(run):
            continue
        for s in run.report["steps"]:
            if s["name"] in want:
                total += 1
                good += s.get("style") == want[s["name"]]
    return good, total


def corridor_sides(left_m: np.ndarray, right_m: np.ndarray, *, sight_m: float = 2.0) -> tuple[float, float]:
    """Median distance (m) to the left and right walls over the ticks with both walls in sight.

    Means over doors, openings and crossings measure the building more than the robot (the paper
    says as much of its Fig. 10); NaN when no tick has both walls in sight.
    """
    both = (left_m < sight_m) & (right_m < sight_m)
    if not both.any():
        return float("nan"), float("nan")
    return float(np.median(left_m[both])), float(np.median(right_m[both]))


def style_errors(
    learned: Mapping[str, Learned], runs: Mapping[str, Sequence[PaperRun]]
) -> list[tuple[str, float, float]]:
    """``(label, left error, right error)``: the runs' distance to each wall minus the demonstration's
    (m), both as :func:`corridor_sides`; the task's steps against their goal segments."""
    out = []
    for style in SIDE:
        lr = learned[style]
        demo = corridor_sides(lr.demo_left, lr.demo_right)
        for where in ("tee", "building"):
            rs = runs[f"{style}/{where}"]
            got = corridor_sides(
                np.concatenate([r.left_m for r in rs]), np.concatenate([r.right_m for r in rs])
            )
            out.append((f"{style}\n{where}", got[0] - demo[0], got[1] - demo[1]))
    task = learned["task"]
    seg = read_segmented(task.segmented)
    left, right = task.demo_left, task.demo_right
    done = [r for r in runs["task"] if task_ok(r)]
    steps_of: dict[str, list[str | None]] = {}
    for k, step in enumerate(("reach-red", "reach-green", "reach-blue")):
        if k >= len(seg.segments) or not done:
            continue
        s = seg.segments[k]
        demo = corridor_sides(left[s.start : s.stop], right[s.start : s.stop])
        rl, rr = [], []
        for r in done:
            ticks = steps_of.setdefault(r.log.name, step_of_ticks(r.log))
            mask = np.array([t == step for t in ticks[: len(r.left_m)]], dtype=bool)
            mask = np.pad(mask, (0, len(r.left_m) - len(mask)))
            rl.append(r.left_m[mask])
            rr.append(r.right_m[mask])
        got = corridor_sides(np.concatenate(rl), np.concatenate(rr))
        out.append((f"task\n{step}", got[0] - demo[0], got[1] - demo[1]))
    return out


def weight_stats(table: FusionTable) -> dict[str, Any]:
    """Per goal step: its BAC rows with samples and spreads; overall: median and largest spread."""
    steps = []
    spreads: list[tuple[float, int, str, int]] = []
    for s in table_steps(table):
        rows = []
        for r in s.rows:
            tmax = max((r.trial_std or {}).values(), default=0.0)
            pmax = max((r.std or {}).values(), default=0.0)
            rows.append(
                {
                    "bac": r.bac,
                    "samples": r.samples,
                    "max_trial_std": tmax,
                    "max_std": pmax,
                    "identifiable": r.identifiable,
                    "weights": r.weights,
                }
            )
            spreads.append((tmax, r.samples or 0, s.name, r.bac))
        steps.append({"name": s.name, "goal": s.goal, "bacs": len(s.rows), "rows": rows})
    arr = np.array([x[0] for x in spreads]) if spreads else np.zeros(1)
    worst = max(spreads, default=(0.0, 0, "", 0))
    big = [x[0] for x in spreads if x[1] >= 100]
    return {
        "steps": steps,
        "median_max_trial_std": float(np.median(arr)),
        "largest_trial_std": {"value": worst[0], "samples": worst[1], "step": worst[2], "bac": worst[3]},
        "largest_trial_std_rows_100_samples": float(max(big, default=0.0)),
    }


def passed(runs: Sequence[PaperRun], want: str) -> int:
    """Runs that passed every obstacle (at least 3) on side ``want`` without a collision."""
    centres = [(o.circle[0], o.circle[1]) for o in load_world("obstacles").obstacles if o.circle]
    good = 0
    for r in runs:
        sides = passing_sides(r.pose, centres)
        good += len(sides) >= 3 and set(sides) == {want} and r.report["collisions"] == 0
    return good


def _rate(k: int, n: int) -> str:
    """``k/n``, and with more than one run the Wilson 95 % interval of the rate: the grid's spread."""
    if n <= 1:
        return f"{k}/{n}"
    lo, hi = wilson_interval(k, n)
    return f"{k}/{n} (95 % interval {100 * lo:.0f}–{100 * hi:.0f} %)"


def spread(results: PaperResults) -> dict[str, dict[str, Any]]:
    """The rates over the grid's repeated runs, each with its Wilson 95 % interval (``report.json``)."""
    runs = results.runs
    counts = {
        "task": (sum(task_ok(r) for r in runs["task"]), len(runs["task"])),
        **{s: (passed(runs[s], s.split("-")[1]), len(runs[s])) for s in ("pass-left", "pass-right")},
        **{
            f"{s}/building": (_count(runs[f"{s}/building"], w), len(runs[f"{s}/building"]))
            for s, w in SIDE.items()
        },
    }
    out = {}
    for name, (k, n) in counts.items():
        lo, hi = wilson_interval(k, n)
        out[name] = {"successes": k, "runs": n, "rate": k / n if n else None, "ci95": [lo, hi]}
    return out


#: why a --quick report judges nothing
QUICK_NOTE = "A --quick smoke run: too few runs per controller to agree or differ with the paper."


def rows(results: PaperResults) -> Iterator[Row]:
    """The comparison rows, in the paper's order; a quick (smoke) run measures, but judges nothing."""
    for row in _rows(results):
        if results.quick and row.agrees is not None:
            row = replace(row, agrees=None, note=f"{row.note} {QUICK_NOTE}".strip())
        yield row


def _rows(results: PaperResults) -> Iterator[Row]:
    learned, runs, junctions = results.learned, results.runs, results.junctions
    errors, quick = results.style_errors, results.quick
    yield Row(
        "single wall-attract behaviour set",
        "Sec. V-A Scenario 1; Fig. 5",
        "with one undivided wallAttract the robot hugs the walls whatever the demonstrated style",
        "not rerun by this report (it uses the scenario3 behaviour set throughout)",
        None,
        "By hand: `lfdfuse segment demo.mcap --behaviors scenario1`, then estimate and execute.",
    )
    for style, fig in (
        ("keep-left", "Fig. 6 top left"),
        ("keep-center", "Fig. 6 top right"),
        ("keep-right", "Fig. 6 bottom"),
    ):
        run = runs[f"{style}/tee"][0]
        want = SIDE[style]
        paper = {
            "keep-left": "keeps closer to the left wall during the entire run",
            "keep-center": "no side preference; drifts left, drawn by open doors",
            "keep-right": "keeps to the right wall",
        }[style]
        note = ""
        if style == "keep-center":
            note = "The paper's own centre run drifted left; we judge it by the demonstrated style, centre."
        yield Row(
            f"{style} learned and run in the small world",
            f"Sec. V-A Scenario 3, {fig}",
            paper,
            f"keeps {run.style} ({_lr(run)})",
            run.style == want,
            note,
        )
    parts, ok = [], True
    for style, want in SIDE.items():
        rs = runs[f"{style}/building"]
        n = _count(rs, want)
        ok &= n == len(rs)
        parts.append(f"{style}: {_rate(n, len(rs))} keep {want}")
    yield Row(
        "styles learned in the small world, run in the large one",
        "Sec. V-A Scenario 2; Fig. 9",
        "the learned side preference holds in a different building",
        "; ".join(parts) + " (0 collisions counted as required)",
        ok,
        "The paper shows paths, not counts; we count runs from different corridor starts.",
    )
    yield Row(
        "T-junction (left or right)",
        "Sec. V-A Scenarios 2–3; Fig. 7",
        "left weights turn left, right weights turn right",
        f"left turns {junctions['keep-left']['T']}, right turns {junctions['keep-right']['T']}",
        junctions["keep-left"]["T"] == "left" and junctions["keep-right"]["T"] == "right",
    )
    yield Row(
        "rotated T (straight or left)",
        "Sec. V-A Scenario 2",
        "left weights go left, right weights go straight",
        f"left goes {junctions['keep-left']['rotated T']}, right goes {junctions['keep-right']['rotated T']}",
        junctions["keep-left"]["rotated T"] == "left" and junctions["keep-right"]["rotated T"] == "straight",
    )
    yield Row(
        "centre style at the T-junction",
        "Sec. V-A Scenario 3; Fig. 6 top right",
        "no preferred direction (goes far into the T before turning)",
        f"turns {junctions['keep-center']['T']}; at the rotated T goes {junctions['keep-center']['rotated T']}",
        None,
        "One run per junction cannot show the absence of a preference.",
    )
    b = {s: runs[f"{s}/building"] for s in SIDE}

    def mean(s: str, key: str) -> float:
        return float(np.mean([r.report[key] for r in b[s]]))

    gap = {s: mean(s, "left_range_mean_m") - mean(s, "right_range_mean_m") for s in SIDE}
    yield Row(
        "range-to-wall style measure (large world)",
        "Sec. V-B.2; Fig. 10",
        "left style nearer the left wall, right style nearer the right, centre's two ranges closer together",
        "left − right mean range: " + ", ".join(f"{s} {gap[s]:+.2f} m" for s in SIDE),
        gap["keep-left"] < 0 < gap["keep-right"]
        and abs(gap["keep-center"]) < min(abs(gap["keep-left"]), abs(gap["keep-right"])),
        "The paper's Fig. 10 is measured on a real robot in its building, the values only in the figure.",
    )
    errs = errors
    vals = [abs(v) for e in errs for v in e[1:] if np.isfinite(v)]
    mae = float(np.mean(vals)) if vals else float("nan")
    yield Row(
        "demonstrated vs learned distance to the walls",
        "Sec. V-B.2; Fig. 11 left",
        "the demonstrated distance is not captured perfectly, but the side preference is",
        f"mean |run − demonstration| {mae:.2f} m over {len(errs)} style/world/step pairs "
        "(medians where both walls are within 2 m; fig11-style-error)",
        None,
        "No number in the paper's text to compare with.",
    )
    task = runs["task"]
    done = sum(task_ok(r) for r in task)
    yield Row(
        "three-goal task from several starts",
        "Sec. V-B.1 (Physical Scenario 1)",
        "5 of 6 runs complete (the paper writes 85 %); the failure was a goal the camera missed",
        f"{_rate(done, len(task))} complete red → green → blue without collision",
        done / len(task) >= 5 / 6,
        "Ours is simulated: no lighting changes, perfect target detection within camera reach.",
    )
    good, total = task_steps_kept(task)
    yield Row(
        "style of each step of the task",
        "Sec. V-B.1",
        "every run kept left to goal 1, centre to goal 2, right to goal 3",
        f"{good} of {total} steps of completed runs kept the demonstrated style",
        total > 0 and good == total,
    )
    ws = weight_stats(learned["trials"].table)
    counts = [st["bacs"] for st in ws["steps"][:3]]
    yield Row(
        "BACs per goal",
        "Sec. V-B.3; Figs. 12–14",
        "8, 5 and 9 BACs for goals 1, 2, 3",
        ", ".join(str(c) for c in counts) + " BACs",
        None,
        "The count depends on the building and the route; ours is a simulated building of the paper's topology.",
    )
    worst = ws["largest_trial_std"]
    yield Row(
        f"weights over {learned['trials'].table.estimated_by.get('trials', '?')} trials",
        "Sec. V-B.3; Figs. 12–14",
        "small std everywhere: one solution; the largest std on a BAC with only 21 samples",
        f"median largest std per row {ws['median_max_trial_std']:.3f}; largest {worst['value']:.3f} "
        f"(BAC {worst['bac']} of {worst['step']}, {worst['samples']} samples); "
        f"≤ {ws['largest_trial_std_rows_100_samples']:.3f} on rows with ≥ 100 samples",
        ws["largest_trial_std_rows_100_samples"] < 0.05,
        "Our sampler's spread over trials is small by design; the posterior std (fig12-14-posterior) says how much "
        "the data leaves open, which the paper's trial spread does not measure."
        + (
            f" Quick mode: {learned['trials'].table.estimated_by.get('trials', '?')} trials only."
            if quick
            else ""
        ),
    )
    parts, ok = [], True
    for style in ("pass-left", "pass-right"):
        want = style.split("-")[1]
        rs = runs[style]
        good_runs = passed(rs, want)
        ok &= good_runs == len(rs)
        parts.append(f"{style}: {_rate(good_runs, len(rs))} runs pass every obstacle on the {want}")
    yield Row(
        "obstacle passing",
        "Sec. V-B Physical Scenario 2; Fig. 15",
        "3 runs per controller; the robot passed on the demonstrated side",
        "; ".join(parts),
        ok,
        "The paper had four demonstrations (centre or side, passing left or right); we run two (pass left, pass right).",
    )


def _clean(x: Any) -> Any:
    """Floats rounded to 1e-4 (non-finite ones as None), containers walked: JSON-ready."""
    if isinstance(x, float):
        return None if not math.isfinite(x) else round(x, 4)
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    return x


def numbers(
    results: PaperResults, rows: Sequence[Row], *, figures: Sequence[dict[str, str]] = ()
) -> dict[str, Any]:
    """Every number of the report (``report.json``): the comparison, each demo, each run, the weights."""
    learned = {
        k: {
            "style": v.style,
            "world": v.world,
            "demo": v.demo.name,
            "table": v.table_path.name,
            "seconds": v.seconds,
            "demo_left_range_mean_m": v.demo_left_m,
            "demo_right_range_mean_m": v.demo_right_m,
            "demo_style": v.demo_style,
        }
        for k, v in results.learned.items()
    }
    report: dict[str, Any] = _clean(
        {
            "format": "lfdfuse/paper-report@1",
            "seed": results.seed,
            "quick": results.quick,
            "trials": results.trials,
            "comparison": [r.as_dict() for r in rows],
            "learned": learned,
            "runs": {k: [r.summary() for r in v] for k, v in results.runs.items()},
            "junctions": {k: dict(v) for k, v in results.junctions.items()},
            "weights": weight_stats(results.learned["trials"].table),
            "spread": spread(results),
            "figures": list(figures),
        }
    )
    return report
