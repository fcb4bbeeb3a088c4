"""Safety of a live run: the speed clamp and the stale-scan watchdog (DESIGN §15).

The network only ever commands from a fresh scan. A scan is *stale* when its stamp does not
advance past the previous scan's, or when it arrives more than ``max_age_s`` later than scans
do (its arrival time minus its stamp exceeds the smallest such difference seen by that much:
a backlog in the link or the driver; a constant offset between the robot's clock and ours
cancels out); and the robot is *blind* when no fresh scan arrived for ``max_age_s`` of
wall-clock time. Blind → a zero Twist
at every watchdog period until scans return. Times are passed in (seconds of a monotonic
clock): tests drive the watchdog without waiting.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from lfdfuse.control.command import DriveParams
from lfdfuse.errors import ConfigError
from lfdfuse.robot.limits import stated_limits

MAX_SCAN_AGE_S = 0.5
#: how often the watchdog looks (and repeats the zero Twist while blind)
WATCHDOG_PERIOD_S = 0.05


@dataclass(frozen=True)
class Limits:
    """Speed and turn-rate limits (m/s, rad/s): every command sent is clamped to them."""

    v_max_mps: float
    omega_max_rps: float

    def clamp(self, v: float, omega: float) -> tuple[float, float]:
        if not (math.isfinite(v) and math.isfinite(omega)):
            return 0.0, 0.0
        return (
            min(max(v, -self.v_max_mps), self.v_max_mps),
            min(max(omega, -self.omega_max_rps), self.omega_max_rps),
        )


def limits_of(
    estimated_by: dict[str, object], *, max_speed: float | None, max_turn: float | None
) -> tuple[Limits, str]:
    """The robot's limits: the table's provenance (``v_max_mps``, ``omega_max_rps``, as an
    imported robot's log has them), else the simulated robot's; clamped by the options."""
    base = DriveParams()
    stated = stated_limits(estimated_by)
    got = [stated[0] or base.v_max_mps, stated[1] or base.omega_max_rps]
    for name, opt in (("--max-speed", max_speed), ("--max-turn", max_turn)):
        if opt is not None and not (math.isfinite(opt) and opt > 0):
            raise ConfigError(f"{name} must be a positive number")
    v = min(got[0], max_speed) if max_speed is not None else got[0]
    w = min(got[1], max_turn) if max_turn is not None else got[1]
    # where each limit comes from: the option that clamped it, the table's robot, or ours
    sources = [
        opt if value < own else ("the table's robot" if said is not None else "the simulated robot's")
        for opt, value, own, said in (
            ("--max-speed", v, got[0], stated[0]),
            ("--max-turn", w, got[1], stated[1]),
        )
    ]
    if sources[0] == sources[1]:
        whence = sources[0]
    else:
        whence = f"speed: {sources[0]}; turn: {sources[1]}"
    if "the simulated robot's" in sources:
        whence += " (the table does not say)"
    return Limits(v, w), whence


class Watchdog:
    """Decides whether a scan is fresh and whether the robot is blind (see the module docstring)."""

    def __init__(self, *, max_age_s: float = MAX_SCAN_AGE_S) -> None:
        self.max_age_s = max_age_s
        self.last_stamp_ns: int | None = None
        self.min_lag_s: float | None = None  # the smallest arrival − stamp seen: the link's own delay
        self.last_fresh_s: float | None = None  # when a fresh scan last gave a command

    def scan(self, stamp_ns: int, now_s: float) -> str:
        """'' for a fresh scan (and remember it), else why it is stale."""
        if self.last_stamp_ns is not None and stamp_ns <= self.last_stamp_ns:
            return "its stamp does not advance"
        lag = now_s - stamp_ns / 1e9
        if self.min_lag_s is None or lag < self.min_lag_s:
            self.min_lag_s = lag
        late = lag - self.min_lag_s
        if late > self.max_age_s:
            return f"it arrived {late:.2f} s later than scans do"
        self.last_stamp_ns = stamp_ns
        return ""

    def commanded(self, now_s: float) -> None:
        """A fresh scan gave a command: the robot sees. (A fresh scan the network could not use —
        its mounting unknown, a foreign beam layout — leaves the robot blind.)"""
        self.last_fresh_s = now_s

    def blind(self, now_s: float) -> bool:
        """No command from a fresh scan for longer than ``max_age_s`` (or none yet)."""
        return self.last_fresh_s is None or now_s - self.last_fresh_s > self.max_age_s

    def reset(self) -> None:
        """A new connection: a new stream (its stamps may restart), nothing fresh yet."""
        self.last_stamp_ns = self.min_lag_s = self.last_fresh_s = None
