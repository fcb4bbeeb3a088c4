"""The teleop session's clocks: the wall clock a person drives on, and a simulated one a script
runs on faster than real time (:class:`~lfdfuse.sources.teleop.session.TeleopSession` waits on
whichever it is given, once per control period)."""

from __future__ import annotations

import time
from typing import Protocol


class Clock(Protocol):
    """Seconds since an arbitrary origin, and a wait until a time (never longer than one period:
    a stop is seen at the next period, so no wait needs to be cut short)."""

    def now(self) -> float: ...

    def wait_until(self, t_s: float) -> None: ...


class WallClock:
    """Real time (``time.monotonic``)."""

    def now(self) -> float:
        return time.monotonic()

    def wait_until(self, t_s: float) -> None:
        delay = t_s - time.monotonic()
        if delay > 0:
            time.sleep(delay)  # a signal's handler runs during it (PEP 475 resumes the rest)


class SimClock:
    """Simulated time: waiting only moves the clock, so scripted runs go as fast as they can."""

    def __init__(self) -> None:
        self.t_s = 0.0

    def now(self) -> float:
        return self.t_s

    def wait_until(self, t_s: float) -> None:
        self.t_s = max(self.t_s, t_s)
