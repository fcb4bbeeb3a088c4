"""The person model chosen by the data: each demo's command model by cross-validated prediction.

How a demo was commanded — on the drive mapping (``continuous``: a script, a joystick, a
proportional controller) or by a few held commands (``discrete``: a keyboard, a teleop panel),
and for the latter how often a press is a slip (the lapse ``λ``) — is read from the log by
counting distinct commands (:mod:`lfdfuse.segment.commands`). Key repeat, gamepads and speed keys
blur that count. With ``EstimateOptions.select_model`` the demo chooses instead: its informative
decisions are cut into :data:`INNER_FOLDS` contiguous blocks, every candidate of
:data:`CANDIDATES` is fitted on the others and predicts the held-out decisions' headings (the
fused vector of the row the step falls in; a step whose row the fit never saw, straight ahead),
and the candidate with the least mean absolute heading error is used — ties and a demo of fewer
than :data:`MIN_DECISIONS` decisions keep the detected model. The choice and every candidate's
error go in the table's provenance.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.commands import commands_of
from lfdfuse.estimate.methods import EstimateOptions
from lfdfuse.network.table import Step
from lfdfuse.segment.read import SegmentedRun

#: one demo's fit: its network steps, one per goal segment in order
Fit = Callable[[SegmentedRun, EstimateOptions], Sequence[Step]]

#: blocks of the inner cross-validation
INNER_FOLDS = 3
#: fewest informative decisions a demo chooses its model on
MIN_DECISIONS = 15
#: the person models tried: command model and lapse
CANDIDATES: tuple[tuple[Literal["continuous", "discrete"], float], ...] = (
    ("discrete", 0.02),
    ("discrete", 0.2),
    ("continuous", 0.02),
)


@dataclass(frozen=True)
class PersonChoice:
    """The chosen command model and lapse, and each candidate's held-out error (°)."""

    mode: Literal["continuous", "discrete"]
    lapse: float
    errors_deg: tuple[tuple[str, float], ...]

    def provenance(self) -> dict[str, object]:
        return {
            "chosen": f"{self.mode}" + (f", lapse {self.lapse:g}" if self.mode == "discrete" else ""),
            "by": f"{INNER_FOLDS}-fold prediction of the demo's own decisions",
            "errors_deg": {name: round(e, 2) for name, e in self.errors_deg},
        }


def _name(mode: str, lapse: float) -> str:
    return mode if mode == "continuous" else f"discrete lapse {lapse:g}"


def _predict(run: SegmentedRun, steps: Sequence[Step], idx: np.ndarray) -> np.ndarray:
    """Fused headings (rad) at steps ``idx`` from estimated network ``steps`` (0 where unseen)."""
    pos = {s.index: i for i, s in enumerate(run.segments)}
    out = np.zeros(len(idx))
    for j, i in enumerate(idx.tolist()):
        st = steps[pos[int(run.segment_of[i])]]
        row = next((r for r in st.fusion if r.bac == int(run.bac[i])), None)
        if row is None:
            continue
        v = np.zeros(2)
        for name, w in row.weights.items():
            v += w * run.vectors[i, run.names.index(name)]
        out[j] = np.arctan2(v[1], v[0]) if np.hypot(v[0], v[1]) > 1e-12 else np.pi / 2
    return out


def choose_person_model(run: SegmentedRun, opts: EstimateOptions, fit: Fit) -> PersonChoice | None:
    """The candidate with the least held-out heading error on ``run``'s own decisions (see the
    module docstring), each fitted by ``fit(run, opts)`` (one demo's network steps); None when the
    demo has too few decisions."""
    base = replace(opts, select_model=False)
    detected = commands_of(run, requested=base.commands, recheck_s=base.model.recheck_s)
    dec = run.informative if detected.decisions is None else run.informative & detected.decisions
    units = np.nonzero(dec)[0]
    if len(units) < MIN_DECISIONS:
        return None
    blocks = np.array_split(units, INNER_FOLDS)
    starts = [0, *(int(b[0]) for b in blocks[1:])]
    ranges = list(zip(starts, [*starts[1:], len(run.t_ns)], strict=True))
    heading = np.arctan2(run.demo[:, 1], run.demo[:, 0])
    errors: list[tuple[str, float]] = []
    for mode, lapse in CANDIDATES:
        eo = replace(base, commands=mode, model=replace(base.model, lapse=lapse))
        err = []
        for a, b in ranges:
            fold = np.zeros(len(run.t_ns), dtype=bool)
            fold[a:b] = True
            train = replace(run, informative=run.informative & ~fold)
            held = np.nonzero(dec & fold)[0]
            if not len(held) or not train.informative.any():
                continue
            try:
                steps = fit(train, eo)
            except ConfigError:  # a candidate that cannot fit a fold is not chosen
                err = [np.inf]
                break
            d = _predict(run, steps, held) - heading[held]
            err.extend(np.abs(np.remainder(d + np.pi, 2 * np.pi) - np.pi).tolist())
        errors.append((_name(mode, lapse), float(np.degrees(np.mean(err))) if err else np.inf))
    best = int(np.argmin([e for _, e in errors]))
    mode, lapse = CANDIDATES[best]
    return PersonChoice(mode, lapse, tuple(errors))
