"""Config files checked against the JSON schemas we ship (``schemas/``), with errors naming the key.

The schemas say the shape (types, required and unknown keys, sizes); the parsers that follow
(:mod:`lfdfuse.world.parse`, :mod:`lfdfuse.network.table`, :mod:`lfdfuse.sources.tasks`) say the
meaning (geometry, BAC ranges, targets that exist), reading every number through :func:`number`
or :func:`integer`: the type is checked before any arithmetic, then finiteness and the range.

>>> validate({"task": [{"style": "keep-left"}]}, "task", origin="t.yaml")
>>> validate({"task": [{"style": "moonwalk"}]}, "task", origin="t.yaml")
Traceback (most recent call last):
...
lfdfuse.errors.ConfigError: t.yaml: task[0].style: unknown value 'moonwalk' (valid: keep-left, ...)
"""

from __future__ import annotations

import json
import math
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
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**60:
        return f"an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"  # repr is slow past 4300
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def number(
    value: Any,
    where: str,
    *,
    error: type[LfdError] = ConfigError,
    lo: float = -math.inf,
    hi: float = math.inf,
) -> float:
    """``value`` as a finite float in ``[lo, hi]``, else ``error`` naming ``where``.

    >>> number(3, "start[0]")
    3.0
    >>> number(10**400, "start[0]")
    Traceback (most recent call last):
    ...
    lfdfuse.errors.ConfigError: start[0] must be a finite number, got an integer of about 401 digits
    >>> number("1.5", "fit_error_deg")
    Traceback (most recent call last):
    ...
    lfdfuse.errors.ConfigError: fit_error_deg must be a finite number, got '1.5'
    """
    want = "a finite number" if lo == -math.inf and hi == math.inf else f"a number in [{lo:g}, {hi:g}]"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise error(f"{where} must be {want}, got {_short(value)}")
    try:
        x = float(value)
    except OverflowError:
        raise error(f"{where} must be {want}, got {_short(value)}") from None
    if not (math.isfinite(x) and lo <= x <= hi):
        raise error(f"{where} must be {want}, got {_short(value)}")
    return x


def integer(
    value: Any,
    where: str,
    *,
    error: type[LfdError] = ConfigError,
    lo: int | None = None,
    hi: int | None = None,
) -> int:
    """``value`` as an integer in ``[lo, hi]`` (either bound optional), else ``error`` naming ``where``.

    >>> integer(2**100, "bac", lo=0, hi=63)
    Traceback (most recent call last):
    ...
    lfdfuse.errors.ConfigError: bac must be an integer in [0, 63], got 1267650600228229401496703205376
    """
    if (
        isinstance(value, bool)
        or not isinstance(value, int)
        or (lo is not None and value < lo)
        or (hi is not None and value > hi)
    ):
        span = (
            f" in [{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}]"
            if lo is not None or hi is not None
            else ""
        )
        raise error(f"{where} must be an integer{span}, got {_short(value)}")
    return value


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
