"""Tasks for the scripted teacher (DESIGN §9): goals chained with styles, as a YAML file says them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from lfdfuse.errors import ConfigError
from lfdfuse.files import read_yaml
from lfdfuse.validate import validate

STYLES = ("keep-left", "keep-center", "keep-right", "slalom", "pass-left", "pass-right")


@dataclass(frozen=True)
class Leg:
    """One part of a task: reach ``target`` (or tour when None) in ``style``."""

    target: str | None
    style: str


def parse_style(name: str) -> str:
    if name not in STYLES:
        raise ConfigError(f"unknown teacher style {name!r} (built-in styles: {', '.join(STYLES)})")
    return name


def parse_task(data: Any, *, origin: str) -> list[Leg]:
    """Validate a task mapping ``{task: [{target, style}, ...]}``."""
    if not isinstance(data, dict) or set(data) != {"task"}:
        keys = sorted(set(data) - {"task"}) if isinstance(data, dict) else []
        extra = f": unknown key {keys[0]!r}" if keys else ""
        raise ConfigError(f"{origin}: a task file is a mapping with one key 'task'{extra}")
    legs = data["task"]
    if not isinstance(legs, list) or not legs:
        raise ConfigError(f"{origin}: 'task' must be a non-empty list of {{target, style}}")
    out: list[Leg] = []
    for i, leg in enumerate(legs):
        if not isinstance(leg, dict):
            raise ConfigError(f"{origin}: task[{i}] must be a mapping {{target, style}}")
        bad = sorted(set(leg) - {"target", "style"})
        if bad:
            raise ConfigError(f"{origin}: task[{i}]: unknown key {bad[0]!r} (valid: target, style)")
        if "style" not in leg:
            raise ConfigError(f"{origin}: task[{i}] needs a 'style'")
        target = leg.get("target")
        out.append(Leg(None if target is None else str(target), parse_style(str(leg["style"]))))
    validate(data, "task", origin=origin)  # what the checks above leave: types, names, sizes
    return out


def load_task(path: str) -> list[Leg]:
    return parse_task(read_yaml(path, what="task file"), origin=path)
