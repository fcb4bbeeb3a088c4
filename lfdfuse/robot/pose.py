"""Where the robot is: a planar pose in the map frame (REP-103)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from lfdfuse.errors import ConfigError


@dataclass(frozen=True)
class Pose:
    """Robot pose in the map frame: metres and radians (REP-103)."""

    x: float
    y: float
    theta: float

    @staticmethod
    def parse(text: str) -> Pose:
        """Parse ``"X,Y,THETA"``."""
        parts = text.split(",")
        try:
            x, y, th = (float(p) for p in parts)
        except ValueError:
            raise ConfigError(f"pose must be X,Y,THETA (three numbers), got {text!r}") from None
        if not all(math.isfinite(v) for v in (x, y, th)):
            raise ConfigError(f"pose must be finite, got {text!r}")
        return Pose(x, y, th)

    def as_tuple(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.theta)
