"""Where the laser sits: the mounting from tf, and scans turned into the robot's base frame.

As ``import`` does (DESIGN §11), with the same conversion (:mod:`lfdfuse.robot.ros`,
:mod:`lfdfuse.robot.mount`): the chain of transforms from the scan's frame up to the base
frame (the odometry's child frame, else ``base_link`` / ``base_footprint``) gives a planar
:class:`~lfdfuse.robot.mount.Mount`; the beams are then re-based so bearing 0 is the robot's
forward, an upside-down scanner has its beams reversed, and a 360° + 1 scanner loses its
repeated last beam. Live, the latest transform of a frame wins.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lfdfuse.drive.decode import LiveTf
from lfdfuse.robot.mount import Mount, base_geometry
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.robot.records import ScanRecord, same_geometry
from lfdfuse.robot.ros import laser_mount, on_the_robot


@dataclass
class TfTree:
    """The static part of the tf tree seen so far: child → (parent, 4×4 transform)."""

    edges: dict[str, tuple[str, np.ndarray]] = field(default_factory=dict)

    def add(self, tf: LiveTf) -> None:
        for tr in tf.transforms:
            if on_the_robot(tr.parent, tr.child):
                self.edges[tr.child] = (tr.parent, np.array(tr.matrix))

    def mount(self, laser: str, bases: tuple[str, ...]) -> tuple[Mount, str] | None:
        """The laser's mounting in the first base frame its chain reaches (None: not known yet)."""
        found = laser_mount(self.edges, laser, bases)
        return None if found is None else (found.mount, found.describe("tf"))


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
        return same_geometry(rec, self.first)

    def ranges(self, rec: ScanRecord) -> np.ndarray:
        """``(B,)`` base-frame ranges, no return = the max range (what the behaviours read)."""
        r = rec.ranges_m[:-1] if self.closing else rec.ranges_m
        if self.reverse:
            r = r[::-1]
        return np.where(np.isfinite(r), r, self.geometry.max_range_m)
