"""``estimate``: from segmented demos to a fusion table (paper Sections IV-B and IV-C).

One demo's rows are :mod:`lfdfuse.estimate.segments` (every goal segment and BAC in one pass of
the method); several demos pooled, :mod:`lfdfuse.estimate.pooled_estimate`. This module checks the demos,
names the network and writes the provenance. Reading the log and refining the table with
sub-goals are the caller's (:mod:`lfdfuse.learn`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.demo_alignment import same_behaviors
from lfdfuse.estimate.methods import EstimateOptions, Method, estimate_group, estimate_groups, provenance
from lfdfuse.estimate.model import CommandBins
from lfdfuse.estimate.pooled_estimate import estimate_pooled
from lfdfuse.estimate.segments import groups_of
from lfdfuse.network.table import FusionTable, Network, default_weights_for
from lfdfuse.progress import Progress
from lfdfuse.segment.read import SegmentedRun

# the options and the row estimators, for callers that import them from here
__all__ = ["EstimateOptions", "Method", "estimate_group", "estimate_groups", "estimate_run", "estimate_runs"]


def estimate_runs(
    runs: Sequence[SegmentedRun],
    *,
    opts: EstimateOptions,
    names: Sequence[str],
    progress: Progress | None = None,
    command_set: CommandBins | None = None,
) -> tuple[FusionTable, int, int]:
    """The fusion table of one or more segmented runs pooled (named ``names``, the first names the
    network); returns it with the row and skipped counts. Several demos must share their
    behaviour set; the provenance lists them (``sources``). ``command_set``: the discrete
    model's command set, when not the first demo's own (held-out evaluation's oracle)."""
    if not runs or len(runs) != len(names):
        raise ConfigError("estimate needs at least one demonstration")
    why = same_behaviors(runs, names)
    if why is not None:
        raise ConfigError(why)
    # a demo without one informative step (no key pressed, only stops and reversing) has nothing
    # to learn from: an error, not a table of default weights that looks like a result
    if not any(len(g.steps) for run in runs for g in groups_of(run)):
        steps = sum(len(run.t_ns) for run in runs)
        raise ConfigError(
            f"{names[0]}: nothing to learn: none of its {steps} steps carries a heading with a"
            " behaviour applicable (standing still and reversing carry no heading); drive the robot"
            " forward or turning while teaching"
        )
    est = estimate_pooled(runs, opts=opts, progress=progress, command_set=command_set)
    by = provenance(
        opts,
        source=names[0],
        commands=est.commands,
        lag_s=runs[0].metadata.get("segment_lag_s"),
        bins=est.bins,
    )
    if est.hierarchy is not None:  # a discrete demo's rows: the prior centred on their steps
        by["prior"] = (
            f"dirichlet({opts.model.alpha:g} + c·step weights), c = {est.hierarchy.spread:g}"
            " by evidence over the rows"
        )
    if est.person is not None:  # the command model the demo chose by cross-validation
        by["person_model"] = est.person.provenance()
    if len(runs) > 1:
        by["sources"] = list(names)
        by["source_commands"] = list(est.source_commands)  # each demo's own command model
        by["source_lags_s"] = [r.metadata.get("segment_lag_s") for r in runs]  # each demo's own lag
    table = FusionTable(
        runs[0].names,
        est.default_weights or default_weights_for(runs[0].names),
        Network(Path(names[0]).stem.split(".")[0], est.steps),
        by,
    )
    return table, est.groups, est.skipped


def estimate_run(
    run: SegmentedRun,
    *,
    opts: EstimateOptions,
    name: str = "demo",
    progress: Progress | None = None,
    command_set: CommandBins | None = None,
) -> tuple[FusionTable, int, int]:
    """The fusion table of a segmented run; returns it with the group and skipped counts."""
    return estimate_runs([run], opts=opts, names=[name], progress=progress, command_set=command_set)
