"""What the demonstration says: the observations the primitives see, and the demonstrated heading.

The demonstrated heading comes from ``/cmd_vel`` held to each scan time (optionally the command
issued ``lag`` later: teachers and people react late), through the inverse of the vector ↔
command mapping. Steps where the robot neither moves nor turns, or reverses, carry no heading
and are kept out of estimation. All time arithmetic is in int64 nanoseconds.
"""

from __future__ import annotations

import math
import re

import numpy as np

from lfdfuse.behaviors.primitives import Observations
from lfdfuse.control.command import DriveParams, command_to_vector
from lfdfuse.errors import LfdError, LogError
from lfdfuse.files import parse_yaml
from lfdfuse.log.reader import Run, hold

#: a target name a world may give (as in the world schema)
TARGET_NAME = re.compile(r"[A-Za-z0-9_]{1,64}")


def target_names_of(run: Run) -> list[str]:
    """Targets of the run's world (attached world file), else those the camera ever saw."""
    if run.world_yaml:
        try:
            data = parse_yaml(run.world_yaml, origin="the attached world.yaml")
        except LfdError:
            data = None  # the attachment is only a hint: a broken one is ignored
        targets = data.get("targets") if isinstance(data, dict) else None
        names = [
            t["name"]
            for t in (targets if isinstance(targets, list) else [])
            if isinstance(t, dict) and isinstance(t.get("name"), str) and TARGET_NAME.fullmatch(t["name"])
        ]
        if names:
            return list(dict.fromkeys(names))
    seen: list[str] = []
    for dets in run.detections:
        for d in dets:
            if d.name not in seen:
                seen.append(d.name)
    return seen


def observations_of(run: Run) -> Observations:
    sg = run.sonar_geometry
    return Observations.from_detections(
        ranges_m=run.ranges_m,
        geometry=run.geometry,
        detections=run.detections,
        target_names=target_names_of(run),
        sonar_m=run.sonar_m,
        sonar_angles_rad=None if sg is None else sg.angles,
        sonar_max_m=math.inf if sg is None else sg.max_range_m,
        pose=run.pose,
    )


def lag_ns_of(lag_s: float) -> int:
    """A lag in seconds as integer nanoseconds."""
    if not math.isfinite(lag_s) or abs(lag_s) > 60.0:
        raise LogError(f"--lag must be a finite number of seconds within ±60, got {lag_s}")
    return int(round(lag_s * 1e9))


def demonstrated(run: Run, drive: DriveParams, *, lag_ns: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``V_r (N, 2)`` and the informative mask ``(N,)`` on the scan clock.

    The scan at ``t`` is paired with the command in force at ``t + lag_ns`` (int64 arithmetic).
    """
    if len(run.cmd_t_ns) == 0:
        raise LogError("the log has no /cmd_vel messages")
    order = np.argsort(run.cmd_t_ns, kind="stable")  # real logs arrive out of order
    ct, cv, cw = run.cmd_t_ns[order], run.cmd_v_mps[order], run.cmd_omega_rps[order]
    when = run.t_ns + np.int64(lag_ns)
    idx = hold(ct, when)
    before = when < ct[0]
    vr, ok = command_to_vector(cv[idx], cw[idx], drive)
    return vr, ok & ~before & np.isfinite(cv[idx]) & np.isfinite(cw[idx])
