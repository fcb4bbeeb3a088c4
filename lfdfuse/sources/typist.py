"""A simulated typist: a scripted teacher pressing keys as a person at a keyboard would (``simulate --keys PERIOD``, DESIGN §9).

:class:`KeyboardPerson` wraps any command source that knows where it wants to go (a style or
task teacher) and drives the robot the way a person at ``teleop_twist_keyboard`` does: every
``period_s`` seconds (jittered, seeded) it looks at what the teacher wants *now* — as of
``reaction_s`` ago: people react late — and presses the forward key whose command points
nearest to it (``i`` straight, ``u``/``o`` arcs, ``j``/``l`` turns in place), then holds that
key's command until the next press. The key table and the held speeds are those of
:mod:`lfdfuse.sources.teleop.keys`; "nearest" compares the headings the commands stand for
under the drive mapping (:func:`~lfdfuse.control.command.command_to_heading`), so a wanted turn of
more than about 65° is a turn in place. The loop runs on the simulated clock (faster than real
time); every press is recorded on ``/teleop/input`` as a teleop log records it.

>>> from lfdfuse.control.command import DriveParams
>>> nearest_key(0.0, DriveParams()), nearest_key(0.5, DriveParams()), nearest_key(-2.0, DriveParams())
('i', 'u', 'l')
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from lfdfuse.control.command import DriveParams, command_to_heading
from lfdfuse.log.writer import LogWriter
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.loop import GoalSource
from lfdfuse.sources.teleop.inputs import SCHEMA, TOPIC, Input, teleop_input
from lfdfuse.sources.teleop.keys import KeyState, press

#: the keys a person driving forward uses (teleop_twist_keyboard's forward half and turns in place)
FORWARD_KEYS: tuple[str, ...] = ("i", "u", "o", "j", "l")


@dataclass(frozen=True)
class KeyboardParams:
    """How the keyboard person presses."""

    period_s: float = 0.5  # mean time between presses
    jitter: float = 0.4  # each interval is period × U(1 − jitter, 1 + jitter)
    reaction_s: float = 0.2  # a press answers what the teacher wanted this long ago


def key_headings(keys: KeyState, drive: DriveParams) -> dict[str, float]:
    """The heading (rad) each forward key's command stands for under the drive mapping."""
    out = {}
    for key in FORWARD_KEYS:
        v, w = press(keys, key, drive).state.command
        th, _ = command_to_heading(np.array(v), np.array(w), drive)
        out[key] = float(th)
    return out


def nearest_key(heading_rad: float, drive: DriveParams, keys: KeyState | None = None) -> str:
    """The forward key whose command points nearest ``heading_rad`` (robot frame, rad)."""
    table = key_headings(keys or KeyState(), drive)
    return min(table, key=lambda k: (abs(math.remainder(heading_rad - table[k], math.tau)), k))


class KeyboardPerson:
    """A :class:`~lfdfuse.sim.loop.GoalSource` pressing the key nearest to what ``teacher`` wants."""

    def __init__(
        self,
        teacher: GoalSource,
        *,
        drive: DriveParams,
        dt_s: float,
        rng: np.random.Generator,
        params: KeyboardParams = KeyboardParams(),
        keys: KeyState = KeyState(),
    ) -> None:
        if not (params.period_s > 0 and math.isfinite(params.period_s)):
            raise ValueError("the key period must be a positive number of seconds")
        self.teacher, self.drive, self.dt_s, self.rng, self.p = teacher, drive, dt_s, rng, params
        self.state = keys
        self._headings = key_headings(keys, drive)
        self._wants: deque[float] = deque(maxlen=max(1, round(params.reaction_s / dt_s)) + 1)
        self._next_s = 0.0
        self.presses: list[tuple[int, Input, tuple[float, float]]] = []  # (tick, key, command) not yet logged
        self.count = 0

    @property
    def done(self) -> bool:
        return self.teacher.done

    @property
    def reached(self) -> list[tuple[str, int]]:
        return self.teacher.reached

    def command(self, obs: Observation) -> tuple[float, float]:
        v, w = self.teacher.command(obs)
        th, moving = command_to_heading(np.array(v), np.array(w), self.drive)
        self._wants.append(float(th) if bool(moving) else math.nan)
        t = obs.k * self.dt_s
        if self.teacher.done:
            if self.state.command != (0.0, 0.0):
                self._press("k", obs.k)
            return self.state.command
        if t + 1e-9 >= self._next_s:
            want = self._wants[0]
            key = "k" if math.isnan(want) else self._nearest(want)
            self._press(key, obs.k)
            j = self.p.jitter
            self._next_s = t + self.p.period_s * float(self.rng.uniform(1.0 - j, 1.0 + j))
        return self.state.command

    def _nearest(self, heading: float) -> str:
        h = self._headings
        return min(h, key=lambda k: (abs(math.remainder(heading - h[k], math.tau)), k))

    def _press(self, key: str, k: int) -> None:
        self.state = press(self.state, key, self.drive).state
        self.presses.append((k, Input("key", key, "keyboard"), self.state.command))
        self.count += 1


class PressRecorder:
    """A sink writing the person's presses on ``/teleop/input`` (as a teleop log has them)."""

    def __init__(self, log: LogWriter, person: KeyboardPerson) -> None:
        self.log, self.person = log, person
        log.add_topic(TOPIC, SCHEMA)

    def record(self, obs: Observation, command: tuple[float, float]) -> None:
        for k, inp, cmd in self.person.presses:
            self.log.write(
                TOPIC,
                obs.t_ns,
                teleop_input(
                    obs.t_ns,
                    inp,
                    effect="move" if cmd != (0.0, 0.0) else "stop",
                    command=cmd,
                    wall_s=k * self.person.dt_s,
                ),
            )
        self.person.presses.clear()
