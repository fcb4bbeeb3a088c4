"""Score variants of the person model on a corpus of segmented logs, as ``evaluate`` does
(blocked k-fold, behaviour cloning beside), with the estimator's model changed by keyword:

    python tests/bench/person_variants.py OUT.json 'lapse=0.1,hierarchy=False,select_model=True' LOG.seg.mcap…

The JSON has ``evaluate --json``'s per-log shape (``logs[].path``, ``logs[].methods``), so
``tests/bench/person_corpus.py`` compares it with a corpus run.
"""

from __future__ import annotations

import json
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

from lfdfuse.errors import ConfigError
from lfdfuse.estimate.model import FusionModel
from lfdfuse.estimate.pipeline import EstimateOptions
from lfdfuse.evaluate.cloning import sector_features
from lfdfuse.evaluate.folds import evaluate_folds
from lfdfuse.segment.read import read_segmented_and_run


def _value(text: str) -> object:
    if text in ("True", "False"):
        return text == "True"
    if text == "None":
        return None
    return float(text)


def main(out: str, spec: str, paths: list[str]) -> None:
    kw = {k: _value(v) for k, v in (p.split("=") for p in spec.split(",") if p)}
    select = bool(kw.pop("select_model", False))
    opts = EstimateOptions(model=FusionModel(**kw), select_model=select)  # type: ignore[arg-type]
    logs: list[dict[str, Any]] = []
    for p in paths:
        run, raw = read_segmented_and_run(p)
        try:
            ev = evaluate_folds(run, features=sector_features(raw.ranges_m, raw.geometry), opts=opts)
        except ConfigError as exc:
            logs.append({"path": p, "error": str(exc)})
            continue
        logs.append({"path": p, "methods": {m: asdict(s) for m, s in ev.methods.items()}})
        f = ev.methods["fused"]
        print(Path(p).name[:50], f"{f.heading_error_deg:.1f}", flush=True)
    Path(out).write_text(json.dumps({"logs": logs}, indent=1))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
