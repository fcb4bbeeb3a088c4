"""The one closed loop: observe, ask the command source, record, step.

``simulate`` (a scripted or network teacher), ``execute`` (a learned network) and ``teleop``
(a person) differ only in their :class:`~lfdfuse.sim.simulator.CommandSource` and in what
their sinks record.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.simulator import CommandSource, Simulator

Progress = Callable[[float, float], None]  # (done, total) in seconds of simulated time


class Sink(Protocol):
    """Receives every tick: the observation and the command decided from it."""

    def record(self, obs: Observation, command: tuple[float, float]) -> None: ...


class GoalSource(CommandSource, Protocol):
    """A command source that reports the goals it reached: ``(target, tick)`` in order."""

    @property
    def reached(self) -> list[tuple[str, int]]: ...


@dataclass(frozen=True)
class RunSummary:
    """What happened in a closed-loop run."""

    steps: int
    duration_s: float
    distance_m: float
    collisions: int
    reached: tuple[tuple[str, float], ...]  # (target, time_s) in order
    completed: bool
    out: str
    left_range_mean_m: float
    right_range_mean_m: float
    poses: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, 3)))
    left_m: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    right_m: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))


def side_beam_index(angles: np.ndarray, angle_rad: float) -> int:
    """The beam nearest a bearing (the paper's style measure reads the beams at ±90°)."""
    return int(np.argmin(np.abs(angles - angle_rad)))


def run(
    sim: Simulator,
    source: GoalSource,
    *,
    start: Pose | None,
    duration_s: float,
    sinks: Sequence[Sink] = (),
    stop_on_collision: bool = False,
    progress: Progress | None = None,
    out: str = "",
) -> RunSummary:
    """Drive ``source`` in ``sim`` from ``start`` for at most ``duration_s`` simulated seconds."""
    dt = sim.robot.dt_s
    n_max = int(math.floor(duration_s / dt + 1e-9))
    angles = sim.sensors.laser.geometry.angles
    i_left, i_right = side_beam_index(angles, math.pi / 2), side_beam_index(angles, -math.pi / 2)
    poses = np.zeros((n_max + 1, 3))
    left = np.zeros(n_max + 1)
    right = np.zeros(n_max + 1)
    obs = sim.reset(start)
    steps = 0
    while True:
        k = obs.k
        command = source.command(obs)
        for sink in sinks:
            sink.record(obs, command)
        poses[k] = obs.pose.as_tuple()
        left[k], right[k] = obs.reading.ranges_m[i_left], obs.reading.ranges_m[i_right]
        steps = k + 1
        if progress is not None and k % 50 == 0:
            progress(k * dt, duration_s)
        if source.done or k == n_max:
            break
        obs = sim.step(*command)
        if obs.blocked and stop_on_collision:
            break
    if progress is not None:
        progress(duration_s, duration_s)
    return RunSummary(
        steps=steps,
        duration_s=(steps - 1) * dt,
        distance_m=sim.distance_m,
        collisions=sim.collisions,
        reached=tuple((name, k * dt) for name, k in source.reached),
        completed=source.done,
        out=out,
        left_range_mean_m=float(left[:steps].mean()),
        right_range_mean_m=float(right[:steps].mean()),
        poses=poses[:steps],
        left_m=left[:steps],
        right_m=right[:steps],
    )
