"""Where the laser sits: the mounting from tf, and scans turned into the robot's base frame.

As ``import`` does (DESIGN §11): the chain of transforms from the scan's frame up to the base
frame (the odometry's child frame, else ``base_link`` / ``base_footprint``) gives a planar
:class:`~lfdfuse.sources.importers.records.Mount`; the beams are then re-based so bearing 0 is
the robot's forward, an upside-down scanner has its beams reversed, and a 360° + 1 scanner
loses its repeated last beam. Transforms from a world frame (``odom``, ``map``) move with the
robot and say nothing about the mounting.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lfdfuse.drive.decode import LiveTf
from lfdfuse.sim.sensors import ScanGeometry
from lfdfuse.sources.importers.convert import base_geometry
from lfdfuse.sources.importers.records import Mount, ScanRecord
from lfdfuse.sources.importers.rosbag import mount_of

BASE_FRAMES = ("base_link", "base_footprint")
WORLD_FRAMES = ("odom", "map", "world", "earth")


@dataclass
class TfTree:
    """The static part of the tf tree seen so far: child → (parent, 4×4 transform)."""

    edges: dict[str, tuple[str, np.ndarray]] = field(default_factory=dict)

    def add(self, tf: LiveTf) -> None:
        for tr in tf.transforms:
            if tr.parent not in WORLD_FRAMES and tr.child not in WORLD_FRAMES:
                self.edges[tr.child] = (tr.parent, np.array(tr.matrix))

    def mount(self, laser: str, bases: tuple[str, ...]) -> tuple[Mount, str] | None:
        """The laser's mounting in the first base frame its chain reaches (None: not known yet)."""
        if laser in bases:
            return Mount(), f"the scans are in the base frame {laser!r}"
        frame, m, seen = laser, np.eye(4), {laser}
        while frame not in bases and frame in self.edges:
            parent, tf = self.edges[frame]
            m, frame = tf @ m, parent
            if frame in seen:  # a loop in a malformed tree
                return None
            seen.add(frame)
        if frame not in bases:
            return None
        return mount_of(m), f"tf ({frame} → {laser})"


@dataclass(frozen=True)
class ScanFrame:
    """The base-frame beam layout of a scanner, fixed by its first scan and its mounting."""

    geometry: ScanGeometry
    reverse: bool
    closing: bool
    first: ScanRecord

    @staticmethod
    def of(first: ScanRecord, mount: Mount) -> ScanFrame:
        geom, reverse, closing = base_geometry(first, mount)
        return ScanFrame(geom, reverse, closing, first)

    def matches(self, rec: ScanRecord) -> bool:
        f = self.first
        return (
            rec.count == f.count
            and abs(rec.start_rad - f.start_rad) < 1e-6
            and abs(rec.increment_rad - f.increment_rad) < 1e-9
            and rec.max_range_m == f.max_range_m
        )

    def ranges(self, rec: ScanRecord) -> np.ndarray:
        """``(B,)`` base-frame ranges, no return = the max range (what the behaviours read)."""
        r = rec.ranges_m[:-1] if self.closing else rec.ranges_m
        if self.reverse:
            r = r[::-1]
        return np.where(np.isfinite(r), r, self.geometry.max_range_m)
