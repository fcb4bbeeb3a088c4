"""The fusion table (DESIGN §7): a behaviour network with fusion weights per BAC.

Parsed once, at the edge, into frozen dataclasses; validated with errors that name the path of
the problem (``network.steps[1].fusion[0].weights.avoid: negative weight``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import yaml

from lfdfuse.behaviors import catalogue
from lfdfuse.behaviors.spec import attract_target
from lfdfuse.errors import ConfigError
from lfdfuse.files import read_yaml, write_text_atomic
from lfdfuse.network.landmark_goals import Landmark
from lfdfuse.validate import integer, number

FORMAT = "lfdfuse/fusion-table@1"


@dataclass(frozen=True)
class FusionRow:
    """Weights for one BAC of one step; the rest says what the data supports (from estimate).

    ``std``: posterior standard deviation per weight; ``trial_std``: spread over ``--trials K``
    (sampler noise); ``samples``: informative steps pooled; ``identifiable``: False when the data
    cannot pin these weights and the prior decides (None: not assessed, e.g. a hand-written row).
    """

    bac: int
    weights: dict[str, float]
    std: dict[str, float] | None = None
    samples: int | None = None
    fit_error_deg: float | None = None
    low_samples: bool = False
    trial_std: dict[str, float] | None = None
    identifiable: bool | None = None
    #: pooled demos: the samples the demos after the first added to this row, and the
    #: weights the first demo alone gave it (None: no demo changed the row, or it is new)
    samples_added: int | None = None
    weights_before: dict[str, float] | None = None


@dataclass(frozen=True)
class Step:
    """A fusion primitive (``fusion`` rows) or a nested network, with its goal (None: none)."""

    name: str
    goal: str | None  # target name
    fusion: tuple[FusionRow, ...] = ()
    network: Network | None = None
    #: this step's weights for BACs it never saw (an extension; else the table's default_weights)
    default_weights: dict[str, float] | None = None
    #: a sub-goal recognised from the robot's own sensors (an extension of the paper): the step is
    #: achieved when it is met; such a step has no target goal
    landmark: Landmark | None = None

    def row(self, bac: int) -> FusionRow | None:
        """The first row of ``fusion`` for ``bac`` (None: none)."""
        return self._rows.get(bac)

    @cached_property
    def _rows(self) -> dict[int, FusionRow]:
        """Each BAC's first row, looked up at every tick (twice: the weights, and help)."""
        rows: dict[int, FusionRow] = {}
        for r in self.fusion:
            rows.setdefault(r.bac, r)
        return rows


@dataclass(frozen=True)
class Network:
    name: str
    steps: tuple[Step, ...]


@dataclass(frozen=True)
class FusionTable:
    behaviors: tuple[str, ...]
    default_weights: dict[str, float]
    network: Network
    estimated_by: dict[str, Any] = field(default_factory=dict)

    def goals(self) -> list[str]:
        """Every target a goal names, depth first."""
        out: list[str] = []

        def walk(net: Network) -> None:
            for s in net.steps:
                if s.network is not None:
                    walk(s.network)
                if s.goal is not None:
                    out.append(s.goal)

        walk(self.network)
        return out

    def targets(self) -> list[str]:
        """Targets the table needs: its attract behaviours and goals."""
        need = [t for b in self.behaviors if (t := attract_target(b)) is not None]
        for g in self.goals():
            if g not in need:
                need.append(g)
        return need


def safe_defaults(t: FusionTable) -> FusionTable:
    """``t`` with the weights for unseen BACs made safe, the table's and every step's
    (:func:`~lfdfuse.behaviors.catalogue.safe_default`: ``avoid`` at least at its default role's
    weight); every row as it was."""

    def walk(net: Network) -> Network:
        steps = []
        for st in net.steps:
            if st.network is not None:
                st = replace(st, network=walk(st.network))
            if st.default_weights is not None:
                st = replace(st, default_weights=catalogue.safe_default(st.default_weights, t.behaviors))
            steps.append(st)
        return replace(net, steps=tuple(steps))

    return replace(
        t, default_weights=catalogue.safe_default(t.default_weights, t.behaviors), network=walk(t.network)
    )


def default_weights_for(behaviors: list[str] | tuple[str, ...]) -> dict[str, float]:
    """Safe wandering for BACs never seen in training: avoid, plus the wander behaviours (each
    behaviour's default role in the catalogue)."""
    return catalogue.default_weights_for(behaviors)


# ---------------------------------------------------------------------------- parsing


def _req(d: dict[str, Any], key: str, where: str) -> Any:
    if key not in d:
        raise ConfigError(f"fusion table: {where}: missing field {key!r}")
    return d[key]


def _keys(d: Any, allowed: set[str], where: str) -> dict[str, Any]:
    if not isinstance(d, dict):
        raise ConfigError(f"fusion table: {where} must be a mapping")
    bad = sorted(set(d) - allowed)
    if bad:
        raise ConfigError(
            f"fusion table: {where}: unknown field {bad[0]!r} (valid: {', '.join(sorted(allowed))})"
        )
    return d


def _weights(
    d: Any, behaviors: tuple[str, ...], where: str, *, allow_zero_sum: bool = False
) -> dict[str, float]:
    if not isinstance(d, dict) or not d:
        raise ConfigError(f"fusion table: {where} must be a non-empty mapping of behaviour: weight")
    out: dict[str, float] = {}
    for name, val in d.items():
        if name not in behaviors:
            raise ConfigError(
                f"fusion table: {where}: unknown behaviour {name!r} (the table's behaviors: {', '.join(behaviors)})"
            )
        w = number(val, f"fusion table: {where}.{name}: weight")
        if w < 0:
            raise ConfigError(f"fusion table: {where}.{name}: negative weight {w:g}")
        out[str(name)] = w
    if not allow_zero_sum and sum(out.values()) <= 0:
        raise ConfigError(f"fusion table: {where}: weights sum to zero")
    return out


def _row(d: Any, behaviors: tuple[str, ...], where: str) -> FusionRow:
    d = _keys(
        d,
        {
            "bac",
            "weights",
            "std",
            "trial_std",
            "samples",
            "identifiable",
            "fit_error_deg",
            "low_samples",
            "samples_added",
            "weights_before",
        },
        where,
    )
    bac = _req(d, "bac", where)
    if isinstance(bac, bool) or not isinstance(bac, int) or bac < 0 or bac >= 1 << len(behaviors):
        raise ConfigError(f"fusion table: {where}.bac must be an integer in [0, 2^{len(behaviors)})")
    weights = _weights(_req(d, "weights", where), behaviors, f"{where}.weights", allow_zero_sum=True)
    for name in weights:
        if not bac >> behaviors.index(name) & 1:
            raise ConfigError(
                f"fusion table: {where}.weights.{name}: behaviour is not applicable in BAC {bac}"
            )
    std = None if d.get("std") is None else _weights(d["std"], behaviors, f"{where}.std", allow_zero_sum=True)
    tstd = d.get("trial_std")
    if tstd is not None:
        tstd = _weights(tstd, behaviors, f"{where}.trial_std", allow_zero_sum=True)
    ident = d.get("identifiable")
    if ident is not None and not isinstance(ident, bool):
        raise ConfigError(f"fusion table: {where}.identifiable must be true or false")
    samples = d.get("samples")
    if samples is not None:
        samples = integer(samples, f"fusion table: {where}.samples", lo=0, hi=2**63 - 1)  # a count of steps
    fit = d.get("fit_error_deg")
    if fit is not None:
        fit = number(fit, f"fusion table: {where}.fit_error_deg", lo=0.0)
    low = d.get("low_samples", False)
    if not isinstance(low, bool):
        raise ConfigError(f"fusion table: {where}.low_samples must be true or false")
    added = d.get("samples_added")
    if added is not None:
        added = integer(added, f"fusion table: {where}.samples_added", lo=0, hi=2**63 - 1)
    before = d.get("weights_before")
    if before is not None:
        before = _weights(before, behaviors, f"{where}.weights_before", allow_zero_sum=True)
    return FusionRow(bac, weights, std, samples, fit, low, tstd, ident, added, before)


def _network(d: Any, behaviors: tuple[str, ...], where: str) -> Network:
    d = _keys(d, {"name", "steps"}, where)
    steps_raw = _req(d, "steps", where)
    if not isinstance(steps_raw, list) or not steps_raw:
        raise ConfigError(f"fusion table: {where}.steps must be a non-empty list")
    steps = []
    for i, s in enumerate(steps_raw):
        sw = f"{where}.steps[{i}]"
        s = _keys(s, {"name", "goal", "fusion", "network", "default_weights", "landmark"}, sw)
        goal = s.get("goal")
        if goal is not None:
            goal = _keys(goal, {"target"}, f"{sw}.goal")
            goal = _req(goal, "target", f"{sw}.goal")
            if not isinstance(goal, str) or not goal.strip():
                raise ConfigError(f"fusion table: {sw}.goal.target must be a target's name, got {goal!r}")
        has_f, has_n = "fusion" in s, "network" in s
        if has_f == has_n:
            raise ConfigError(f"fusion table: {sw}: give exactly one of 'fusion' or 'network'")
        if has_n:
            steps.append(
                Step(str(_req(s, "name", sw)), goal, (), _network(s["network"], behaviors, f"{sw}.network"))
            )
        else:
            rows_raw = s["fusion"] or []
            if not isinstance(rows_raw, list):
                raise ConfigError(f"fusion table: {sw}.fusion must be a list")
            rows = tuple(_row(r, behaviors, f"{sw}.fusion[{j}]") for j, r in enumerate(rows_raw))
            if len({r.bac for r in rows}) != len(rows):
                raise ConfigError(f"fusion table: {sw}.fusion names a BAC twice")
            sd = s.get("default_weights")
            sdw = None if sd is None else _weights(sd, behaviors, f"{sw}.default_weights")
            lm = s.get("landmark")
            lmk = None if lm is None else Landmark.from_dict(lm, f"{sw}.landmark")
            if lmk is not None and goal is not None:
                raise ConfigError(f"fusion table: {sw}: a step has a goal or a landmark, not both")
            steps.append(Step(str(_req(s, "name", sw)), goal, rows, None, sdw, lmk))
    return Network(str(d.get("name", "network")), tuple(steps))


def parse_table(data: Any) -> FusionTable:
    d = _keys(data, {"format", "behaviors", "default_weights", "network", "estimated_by"}, "top level")
    fmt = _req(d, "format", "top level")
    if fmt != FORMAT:
        raise ConfigError(f"fusion table: format must be {FORMAT!r}, got {fmt!r}")
    beh = _req(d, "behaviors", "top level")
    if not isinstance(beh, list) or not beh or not all(isinstance(b, str) for b in beh):
        raise ConfigError("fusion table: behaviors must be a non-empty list of names")
    for b in beh:
        if catalogue.spec_of(b) is None:
            raise ConfigError(
                f"fusion table: unknown behaviour {b!r} in behaviors (valid: {', '.join(catalogue.BASE_BEHAVIORS)}, attract_<target>)"
            )
    if len(set(beh)) != len(beh):
        raise ConfigError("fusion table: behaviors names a behaviour twice")
    behaviors = tuple(beh)
    default = _weights(_req(d, "default_weights", "top level"), behaviors, "default_weights")
    net = _network(_req(d, "network", "top level"), behaviors, "network")
    est = d.get("estimated_by") or {}
    return FusionTable(behaviors, default, net, dict(est) if isinstance(est, dict) else {})


def load_table(path: str | Path) -> FusionTable:
    return parse_table(read_yaml(path, what="fusion table"))


# ---------------------------------------------------------------------------- writing


def _r(x: float) -> float:
    return round(float(x), 4)


def _row_dict(r: FusionRow) -> dict[str, Any]:
    d: dict[str, Any] = {"bac": r.bac, "weights": {k: _r(v) for k, v in r.weights.items()}}
    if r.std is not None:
        d["std"] = {k: _r(v) for k, v in r.std.items()}
    if r.trial_std is not None:
        d["trial_std"] = {k: _r(v) for k, v in r.trial_std.items()}
    if r.samples is not None:
        d["samples"] = r.samples
    if r.identifiable is not None:
        d["identifiable"] = r.identifiable
    if r.fit_error_deg is not None:
        d["fit_error_deg"] = round(r.fit_error_deg, 2)
    if r.low_samples:
        d["low_samples"] = True
    if r.samples_added is not None:
        d["samples_added"] = r.samples_added
    if r.weights_before is not None:
        d["weights_before"] = {k: _r(v) for k, v in r.weights_before.items()}
    return d


def _net_dict(n: Network) -> dict[str, Any]:
    steps = []
    for s in n.steps:
        d: dict[str, Any] = {"name": s.name, "goal": None if s.goal is None else {"target": s.goal}}
        if s.network is not None:
            d["network"] = _net_dict(s.network)
        else:
            if s.landmark is not None:
                d["landmark"] = s.landmark.to_dict()
            if s.default_weights is not None:
                d["default_weights"] = {k: _r(v) for k, v in s.default_weights.items()}
            d["fusion"] = [_row_dict(r) for r in s.fusion]
        steps.append(d)
    return {"name": n.name, "steps": steps}


def table_dict(t: FusionTable) -> dict[str, Any]:
    d: dict[str, Any] = {
        "format": FORMAT,
        "behaviors": list(t.behaviors),
        "default_weights": {k: _r(v) for k, v in t.default_weights.items()},
        "network": _net_dict(t.network),
    }
    if t.estimated_by:
        d["estimated_by"] = t.estimated_by
    return d


def dump_table(t: FusionTable) -> str:
    return yaml.safe_dump(table_dict(t), sort_keys=False, default_flow_style=None, width=120)


def write_table(t: FusionTable, path: str | Path) -> None:
    """Write atomically: a temp file in the same folder, then rename."""
    write_text_atomic(path, dump_table(t))


@dataclass(frozen=True)
class StepRows:
    """One fusion primitive of a table: its name (nested steps as ``outer/inner``), goal and rows."""

    name: str
    goal: str | None
    rows: tuple[FusionRow, ...]


def named_leaf_steps(table: FusionTable) -> list[tuple[str, Step]]:
    """The fusion steps of a (nested) network, depth first (the order of the goal segments), each
    with its name (a nested network's steps as ``outer/inner``)."""
    out: list[tuple[str, Step]] = []

    def walk(net: Network, prefix: str) -> None:
        for s in net.steps:
            if s.network is not None:
                walk(s.network, f"{prefix}{s.name}/")
            else:
                out.append((f"{prefix}{s.name}", s))

    walk(table.network, "")
    return out


def leaf_steps(table: FusionTable) -> list[Step]:
    """The fusion steps of a (nested) network, depth first: the order of the goal segments."""
    return [s for _, s in named_leaf_steps(table)]


def table_steps(table: FusionTable) -> list[StepRows]:
    """Every fusion primitive of a table with its rows, depth first."""
    return [StepRows(name, s.goal, s.fusion) for name, s in named_leaf_steps(table)]
