"""Config files checked against the JSON schemas we ship (``schemas/``), with errors naming the key.

The schemas say the shape (types, required and unknown keys, sizes); the parsers that follow
(:mod:`lfdfuse.world.model`, :mod:`lfdfuse.network.table`, :mod:`lfdfuse.sources.tasks`) say the
meaning (geometry, BAC ranges, targets that exist).

>>> validate({"task": [{"style": "keep-left"}]}, "task", origin="t.yaml")
>>> validate({"task": [{"style": "moonwalk"}]}, "task", origin="t.yaml")
Traceback (most recent call last):
...
lfdfuse.errors.ConfigError: t.yaml: task[0].style: unknown value 'moonwalk' (valid: keep-left, ...)
"""

from __future__ import annotations

import json
from functools import cache
from importlib import resources
from typing import Any

import jsonschema
from jsonschema.exceptions import best_match

from lfdfuse.errors import ConfigError, LfdError

#: schema file per kind of config
SCHEMAS = {"world": "world.schema.json", "task": "task.schema.json", "table": "fusion-table.schema.json"}


@cache
def _validator(kind: str) -> Any:
    text = (resources.files("lfdfuse") / "schemas" / SCHEMAS[kind]).read_text()
    schema = json.loads(text)
    cls = jsonschema.validators.validator_for(schema)
    return cls(schema)


def key_path(path: Any) -> str:
    """``['walls', 0, 1]`` → ``walls[0][1]``."""
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "top level"


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def validate(data: Any, kind: str, *, origin: str, error: type[LfdError] = ConfigError) -> None:
    """Raise ``error`` naming the key of the most relevant schema violation of ``data``, if any."""
    err = best_match(_validator(kind).iter_errors(data))
    if err is None:
        return
    where = key_path(err.absolute_path)
    if err.validator == "additionalProperties":
        extra = sorted(set(err.instance) - set(err.schema.get("properties", {})))
        valid = ", ".join(sorted(err.schema.get("properties", {})))
        raise error(
            f"{origin}: {where}: unknown key {_short(extra[0] if extra else '?')} (valid keys: {valid})"
        )
    if err.validator == "required":
        missing = [k for k in err.validator_value if isinstance(err.instance, dict) and k not in err.instance]
        raise error(f"{origin}: {where}: missing key {_short(missing[0] if missing else '?')}")
    if err.validator == "type":
        want = err.validator_value
        kind = "a finite number" if want == "number" else f"of type {want}"
        raise error(f"{origin}: {where} must be {kind}, got {_short(err.instance)}")
    if err.validator == "enum":
        valid = ", ".join(str(v) for v in err.validator_value)
        raise error(f"{origin}: {where}: unknown value {_short(err.instance)} (valid: {valid})")
    if err.validator in ("maxItems", "maxLength", "minItems", "minLength"):
        limit = err.validator_value
        size = "at most" if err.validator.startswith("max") else "at least"
        unit = "items" if err.validator.endswith("Items") else "characters"
        raise error(f"{origin}: {where}: must have {size} {limit} {unit}")
    message = err.message
    if len(message) > 160:
        message = f"{_short(err.instance)} is not valid ({err.validator} {_short(err.validator_value)})"
    raise error(f"{origin}: {where}: {message}")
