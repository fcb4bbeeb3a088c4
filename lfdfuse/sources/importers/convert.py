"""A robot log into an lfdfuse demo MCAP (``lfdfuse import``, DESIGN §11).

``/scan`` is a ``foxglove.LaserScan`` in ``base_link``: beam angles are already turned into the
base frame (``start_angle`` = the sensor's start angle + the mount yaw; an upside-down scanner has
its beams reversed), the scan's ``pose`` carries the mount offset so viewers draw each beam from
where the laser sits, and a beam without a return holds the scanner's max range (provenance
``laser_max_range_m``). A 360° scanner that repeats its first bearing as its last beam (the Neato)
loses that last beam. ``/cmd_vel`` holds the commands as recorded (each held until the next), or
commands derived from the poses (``cmd_from=odom``, or when the log has none); ``/pose`` and
``/tf`` the odometry pose (frame ``odom``); ``/targets`` the goals of ``--goals``.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from lfdfuse import __version__
from lfdfuse.log import LogWriter
from lfdfuse.log.messages import frame_transform, laser_scan, pose_in_frame, target_detections, twist
from lfdfuse.robot.commands import WILD_FACTOR, CommandStructure, classify_commands, percentile_limit
from lfdfuse.robot.mount import Mount, base_geometry
from lfdfuse.robot.readings import Detection, ScanGeometry
from lfdfuse.robot.records import ScanRecord, same_geometry
from lfdfuse.sources.importers import open_source
from lfdfuse.sources.importers.derive import commands_from_poses
from lfdfuse.sources.importers.goals import REACH_M, Goal, goal_detections
from lfdfuse.sources.importers.records import Publisher, Source, SourceError, TopicChoice

ODOM_FRAME = "odom"
CmdFrom = Literal["auto", "cmd", "odom"]


@dataclass(frozen=True)
class ImportOptions:
    """How to import (None everywhere: detect or take it from the log)."""

    fmt: str | None = None
    topics: TopicChoice = TopicChoice()
    cmd_from: CmdFrom = "auto"
    mount: Mount | None = None
    v_max_mps: float | None = None
    omega_max_rps: float | None = None
    teacher: Literal["human", "unknown"] = "unknown"
    goals: tuple[Goal, ...] = ()


@dataclass(frozen=True)
class ImportSummary:
    """What ``import`` wrote and left out, for the CLI to show."""

    source: str
    out: str
    format: str
    topics: dict[str, str]
    scans: int
    commands: int
    poses: int
    commands_from: str
    geometry: ScanGeometry
    no_return_fraction: float
    mount: Mount
    mount_from: str
    v_max_mps: float | None
    omega_max_rps: float | None
    limits_from: str
    duration_s: float
    dropped: dict[str, int] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    goals: tuple[str, ...] = ()
    command_model: CommandStructure | None = None
    publishers: tuple[Publisher, ...] = ()
    cmd_publisher: str | None = None
    start_ns: int = 0


def import_log(
    source: str | Path, *, out: str | Path, options: ImportOptions = ImportOptions()
) -> ImportSummary:
    """Import a robot log into an lfdfuse demo MCAP at ``out`` (written atomically)."""
    path = Path(source)
    if Path(out).resolve() == path.resolve():
        raise SourceError("the output must not overwrite the input")
    src = open_source(path, fmt=options.fmt, topics=options.topics)
    return write_demo(src, source=str(source), out=out, options=options)


def write_demo(
    src: Source,
    *,
    source: str,
    out: str | Path,
    options: ImportOptions = ImportOptions(),
    command: str = "import",
) -> ImportSummary:
    """Write an opened :class:`Source` as an lfdfuse demo MCAP at ``out`` (written atomically):
    what ``import`` writes, for a log on disk or for what ``record`` received from a live robot
    (``command`` names the tool in the provenance; ``source`` where the records came from)."""
    path = source
    info = src.info
    notes = list(info.notes)

    scans = sorted(src.iter_scans(), key=lambda s: s.t_ns)
    if not scans:
        raise SourceError(f"{path}: the log has no laser scans")
    first = scans[0]
    kept: list[ScanRecord] = []
    for s in scans:
        if not same_geometry(s, first):
            src.dropped["scan: beam geometry differs from the first scan"] += 1
        elif kept and s.t_ns == kept[-1].t_ns:
            src.dropped["scan: same time stamp as the previous scan"] += 1
        else:
            kept.append(s)
    mount = options.mount or info.mount
    mount_from = "--laser-mount" if options.mount else info.mount_from
    if mount is None:
        mount, mount_from = Mount(), "unknown: assumed at the base, facing forward (use --laser-mount)"
    geom, reverse, closing = base_geometry(first, mount)
    if closing:
        notes.append("the last beam repeats the first bearing (360° + 1): dropped")
    ranges = np.stack([s.ranges_m for s in kept])
    if closing:
        ranges = ranges[:, :-1]
    if reverse:
        ranges = ranges[:, ::-1]
    no_ret = ~np.isfinite(ranges)
    ranges = np.where(no_ret, geom.max_range_m, ranges)
    scan_t = np.array([s.t_ns for s in kept], dtype=np.int64)

    poses = sorted(src.iter_poses(), key=lambda p: p.t_ns)
    pose_arr = np.array([(p.x, p.y, p.theta) for p in poses], dtype=np.float64).reshape(-1, 3)
    pose_t = np.array([p.t_ns for p in poses], dtype=np.int64)

    recorded = sorted(src.iter_commands(), key=lambda c: c.t_ns)
    want_odom = options.cmd_from == "odom" or (options.cmd_from == "auto" and not recorded)
    if options.cmd_from == "cmd" and not recorded:
        raise SourceError(f"{path}: the log has no velocity commands (try --cmd-from odom)")
    if want_odom:
        if recorded:
            src.dropped["command: replaced by commands derived from odometry"] += len(recorded)
        cmd_t, cmd_v, cmd_w = commands_from_poses(pose_t, pose_arr[:, 0], pose_arr[:, 1], pose_arr[:, 2])
        odom = info.topics.get("odom")
        commands_from = f"derived from odometry: {odom}" if len(cmd_t) else "none: no commands, no odometry"
    else:
        cmd_t = np.array([c.t_ns for c in recorded], dtype=np.int64)
        cmd_v = np.array([c.v_mps for c in recorded], dtype=np.float64)
        cmd_w = np.array([c.omega_rps for c in recorded], dtype=np.float64)
        commands_from = f"recorded on {info.topics.get('cmd')}"
        if info.cmd_publisher is not None:
            commands_from += f" by {info.cmd_publisher}"
        elif len(info.publishers) > 1:
            notes.append(
                f"{len(info.publishers)} publishers on {info.topics.get('cmd')}, merged in time order "
                "(keep one with --cmd-publisher NAME)"
            )
    if len(cmd_t) == 0:
        notes.append("no /cmd_vel: the log has neither commands nor odometry, so it cannot be segmented")
    structure = classify_commands(cmd_t, cmd_v, cmd_w) if len(cmd_t) else None

    odom_twist = None
    if len(pose_t) > 1:
        _t, ov, ow = commands_from_poses(pose_t, pose_arr[:, 0], pose_arr[:, 1], pose_arr[:, 2])
        odom_twist = (ov, ow)
    v_max, w_max, limits_from = _limits(
        options, info.v_max_mps, info.omega_max_rps, cmd_v, cmd_w, want_odom, odom=odom_twist, notes=notes
    )
    dt_s = float(np.median(np.diff(scan_t))) / 1e9 if len(scan_t) > 1 else 0.1
    topics = {role: name for role, name in info.topics.items() if role != "cmd" or not want_odom}
    meta = {
        "tool": "lfdfuse",
        "version": __version__,
        "command": command,
        "source": str(source),
        "format": info.format,
        **{f"{role}_topic": name for role, name in topics.items()},
        "cmd_from": "odom" if want_odom else "cmd",
        "laser_max_range_m": repr(geom.max_range_m),
        "laser_mount": ",".join(repr(round(v, 6)) for v in (mount.x_m, mount.y_m, mount.yaw_rad)),
        "laser_mount_from": mount_from,
        "limits_from": limits_from,
        "teacher": options.teacher,
        "dt_s": repr(round(dt_s, 6)),
        "start_ns": str(int(scan_t[0])),
    }
    if structure is not None:
        meta["command_model"] = structure.model
    if info.cmd_publisher is not None:
        meta["cmd_publisher"] = info.cmd_publisher
    elif len(info.publishers) > 1:
        meta["cmd_publishers"] = ",".join(p.name for p in info.publishers)
    if v_max is not None:
        meta["v_max_mps"] = repr(v_max)
    if w_max is not None:
        meta["omega_max_rps"] = repr(w_max)
    detections: list[tuple[Detection, ...]] = []
    if options.goals:
        detections = goal_detections(options.goals, scan_t, pose_t, pose_arr)
        meta["goals"] = ",".join(f"goal_{g.name}" for g in options.goals)
        meta["camera_reach_m"] = repr(REACH_M)

    messages: list[tuple[int, int, str, dict[str, Any]]] = []
    offset = {"position": {"x": mount.x_m, "y": mount.y_m, "z": 0.0}, "orientation": _IDENTITY_Q}
    for i, t in enumerate(scan_t.tolist()):
        msg = laser_scan(t, ranges[i], geom)
        msg["pose"] = offset
        messages.append((t, 2, "/scan", msg))
        if detections:
            messages.append((t, 3, "/targets", target_detections(t, detections[i])))
    for t, (x, y, th) in zip(pose_t.tolist(), pose_arr.tolist(), strict=True):
        p = pose_in_frame(t, x, y, th)
        p["frame_id"] = ODOM_FRAME
        tf = frame_transform(t, x, y, th)
        tf["parent_frame_id"] = ODOM_FRAME
        messages.extend([(t, 0, "/tf", tf), (t, 1, "/pose", p)])
    for t, v, w in zip(cmd_t.tolist(), cmd_v.tolist(), cmd_w.tolist(), strict=True):
        messages.append((t, 4, "/cmd_vel", twist(t, round(v, 6), round(w, 6))))
    messages.sort(key=lambda m: (m[0], m[1]))
    with LogWriter(out, metadata=meta) as log:
        if detections:
            log.add_topic("/targets", "lfdfuse.TargetDetections")
        for t, _, topic, msg in messages:
            log.write(topic, t, msg)

    return ImportSummary(
        source=str(source),
        out=str(out),
        format=info.format,
        topics=topics,
        scans=len(kept),
        commands=len(cmd_t),
        poses=len(poses),
        commands_from=commands_from,
        geometry=geom,
        no_return_fraction=float(no_ret.mean()) if no_ret.size else 0.0,
        mount=mount,
        mount_from=mount_from,
        v_max_mps=v_max,
        omega_max_rps=w_max,
        limits_from=limits_from,
        duration_s=float(scan_t[-1] - scan_t[0]) / 1e9,
        dropped=dict(sorted(Counter(src.dropped).items())),
        notes=tuple(notes),
        goals=tuple(f"goal_{g.name}" for g in options.goals),
        command_model=structure,
        publishers=info.publishers,
        cmd_publisher=info.cmd_publisher,
        start_ns=int(scan_t[0]),
    )


_IDENTITY_Q = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}


def robust_limit(values: np.ndarray, *, derived: bool) -> float | None:
    """A robot limit from commands (speed or turn rate), robust to a few wild ones.

    Recorded commands: the largest nonzero magnitude within :data:`WILD_FACTOR` of their 99th
    percentile (:func:`~lfdfuse.robot.commands.percentile_limit`), so a person follower that
    turned at up to 1.8 rad/s but mostly at 0.1 gets 1.8, not its most common value. Derived commands (odometry
    noise, pose jumps): the 95th percentile of all of them.

    >>> robust_limit(np.array([0.3] * 30 + [0.0] * 10 + [19.9]), derived=False)
    0.3
    """
    a = np.abs(values[np.isfinite(values)])
    if len(a) == 0:
        return None
    if derived:
        return float(np.percentile(a, 95.0))
    return percentile_limit(a)


def _limits(
    options: ImportOptions,
    v_log: float | None,
    w_log: float | None,
    cmd_v: np.ndarray,
    cmd_w: np.ndarray,
    derived: bool,
    odom: tuple[np.ndarray, np.ndarray] | None = None,
    notes: list[str] | None = None,
) -> tuple[float | None, float | None, str]:
    """Robot limits: the options, else the log's parameters, else the commands' robust range.

    Recorded commands give the largest magnitude plausible beside their 99th percentile
    (:func:`robust_limit`); never a wild command's, nor the most common value. Derived commands (odometry noise, pose jumps)
    give their 95th percentile. Where the largest command is implausible beside that (more than
    :data:`WILD_FACTOR` times it, or beyond the odometry's own 95th percentile as much), a note says so.
    """
    v_cmd = robust_limit(cmd_v, derived=derived)
    w_cmd = robust_limit(cmd_w, derived=derived)
    if notes is not None and not derived:
        for name, unit, values, lim, k in (
            ("speed", "m/s", cmd_v, v_cmd, 0),
            ("turn rate", "rad/s", cmd_w, w_cmd, 1),
        ):
            top = float(np.nanmax(np.abs(values[np.isfinite(values)]))) if np.isfinite(values).any() else 0.0
            seen = None if odom is None or len(odom[k]) < 10 else float(np.percentile(np.abs(odom[k]), 95))
            if lim is not None and top > WILD_FACTOR * max(lim, seen or 0.0):
                moved = "" if seen is None else f", odometry's 95th percentile {seen:.3g} {unit}"
                notes.append(
                    f"warning: implausible command {name} up to {top:.3g} {unit}: the limit is the commands' "
                    f"usual {lim:.3g} {unit}{moved} (give --v-max/--omega-max to override)"
                )
    out: list[float | None] = []
    whence: list[str] = []
    for opt, log, cmd in ((options.v_max_mps, v_log, v_cmd), (options.omega_max_rps, w_log, w_cmd)):
        for value, label in ((opt, "option"), (log, "log parameters"), (cmd, "commands' range")):
            if value is not None and value > 0:
                out.append(round(value, 6))
                whence.append(label)
                break
        else:
            out.append(None)
            whence.append("unknown")
    label = whence[0] if whence[0] == whence[1] else f"{whence[0]} / {whence[1]}"
    return out[0], out[1], label
