"""Round trips against hand-written truth tables, and the cost of estimating (``make bench``).

For every shipped truth table (:mod:`lfdfuse.evaluate.roundtrip`): drive the network teacher
with it for a training and a held-out demonstration, segment, estimate (``pf``, and the paper's
filter beside it), and report per row: samples, truth, estimate, least-squares heading fit, the
Cramér–Rao bound on L1, and per demo the held-out heading error over the truth's noise floor and
the ratio of estimating time to simulating time (both measured in this run).

``run(quick)`` returns the rows of the printed table; ``python -m tests.bench.estimate``
prints it.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from lfdfuse.estimate.pipeline import EstimateOptions, Method
from lfdfuse.evaluate.roundtrip import (
    TEACHER_NOISE_RAD,
    compare_rows,
    demonstrate,
    heading_errors,
    load_truth,
    truth_names,
)
from lfdfuse.learn import LearnOptions, learn_run


def _weights(names: tuple[str, ...], w: np.ndarray) -> str:
    return " ".join(f"{n}={x:.2f}" for n, x in zip(names, w, strict=True) if x >= 0.005) or "-"


def run(quick: bool) -> list[dict[str, Any]]:
    """One dict per learned row (``kind: row``) and one per demonstration (``kind: demo``)."""
    names = truth_names()[:1] if quick else truth_names()
    seeds = (1,) if quick else (1, 3)
    duration = 150.0 if quick else 300.0
    out: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            truth, world = load_truth(name)
            held = demonstrate(truth, world, seed=1000, duration_s=duration, folder=Path(tmp))
            floor = float(heading_errors(truth, held.run).mean())
            for seed in seeds:
                demo = demonstrate(truth, world, seed=seed, duration_s=duration, folder=Path(tmp))
                t0 = time.perf_counter()
                learned = learn_run(demo.run, options=LearnOptions(EstimateOptions(seed=seed))).table
                cost = time.perf_counter() - t0
                paper = learn_run(
                    demo.run, options=LearnOptions(EstimateOptions(Method.PAPER, seed=seed))
                ).table
                old = {
                    (r.step, r.bac): r
                    for r in compare_rows(truth, paper, demo.run, noise_rad=TEACHER_NOISE_RAD)
                }
                for r in compare_rows(truth, learned, demo.run, noise_rad=TEACHER_NOISE_RAD):
                    out.append(
                        {
                            "kind": "row",
                            "truth_table": name,
                            "seed": seed,
                            "bac": r.bac,
                            "samples": r.samples,
                            "identifiable": r.identifiable,
                            "truth": _weights(r.names, r.truth),
                            "estimate": _weights(r.names, r.estimate),
                            "fit": _weights(r.names, r.fit),
                            "l1": round(r.l1, 4),
                            "fit_l1": round(r.fit_l1, 4),
                            "paper_l1": round(old[(r.step, r.bac)].l1, 4),
                            "crb_l1": round(r.crb, 4),
                        }
                    )
                out.append(
                    {
                        "kind": "demo",
                        "truth_table": name,
                        "seed": seed,
                        "steps": int(demo.run.informative.sum()),
                        "simulate_s": round(demo.simulate_s, 3),
                        "estimate_s": round(cost, 3),
                        "cost_ratio": round(cost / demo.simulate_s, 3),
                        "floor_deg": round(float(np.degrees(floor)), 3),
                        "heldout_ratio": round(float(heading_errors(learned, held.run).mean()) / floor, 4),
                        "paper_heldout_ratio": round(
                            float(heading_errors(paper, held.run).mean()) / floor, 4
                        ),
                    }
                )
    return out


def render(rows: list[dict[str, Any]]) -> str:
    """The table as fixed-width text."""
    lines = [
        "round trips: per learned row (L1 to the truth: pf | LS heading fit | paper filter | CRB)",
        f"{'truth':16} {'seed':>4} {'bac':>4} {'n':>5} {'id':>3} {'pf':>6} {'fit':>6} {'paper':>6} {'crb':>6}  truth / estimate / fit",
    ]
    for r in rows:
        if r["kind"] != "row":
            continue
        ident = {True: "yes", False: "no", None: "-"}[r["identifiable"]]
        lines.append(
            f"{r['truth_table']:16} {r['seed']:>4} {r['bac']:>4} {r['samples']:>5} {ident:>3} {r['l1']:6.3f} "
            f"{r['fit_l1']:6.3f} {r['paper_l1']:6.3f} {r['crb_l1']:6.3f}  {r['truth']} / {r['estimate']} / {r['fit']}"
        )
    lines += [
        "",
        "per demonstration: held-out heading error / the truth's noise floor; estimate time / simulate time",
        f"{'truth':16} {'seed':>4} {'steps':>6} {'floor°':>7} {'pf':>6} {'paper':>6} {'sim s':>6} {'est s':>6} {'ratio':>6}",
    ]
    for r in rows:
        if r["kind"] == "demo":
            lines.append(
                f"{r['truth_table']:16} {r['seed']:>4} {r['steps']:>6} {r['floor_deg']:7.2f} {r['heldout_ratio']:6.3f} "
                f"{r['paper_heldout_ratio']:6.3f} {r['simulate_s']:6.2f} {r['estimate_s']:6.2f} {r['cost_ratio']:6.2f}"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    ap.add_argument("--quick", action="store_true", help="one truth table, one seed, 150 s demos")
    ap.add_argument("--json", type=Path, help="also write the rows as JSON")
    args = ap.parse_args(argv)
    rows = run(args.quick)
    sys.stdout.write(render(rows) + "\n")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
