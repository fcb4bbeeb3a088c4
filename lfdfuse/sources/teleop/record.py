"""The teleop session's own channels, written each control period as sinks of the one loop: the
person's inputs on ``/teleop/input`` and, with a network, who drove on ``/lfd/authority``."""

from __future__ import annotations

from typing import Protocol

from lfdfuse.log import lfd
from lfdfuse.log.writer import LogWriter
from lfdfuse.robot.readings import Observation
from lfdfuse.sources.teleop.inputs import SCHEMA, TOPIC, Input, teleop_input


class Recorded(Protocol):
    """What the sinks read of a :class:`~lfdfuse.sources.teleop.session.TeleopSession`."""

    @property
    def authority(self) -> str:
        """Who drives now: ``network`` or ``person``."""

    @property
    def authority_source(self) -> str:
        """The person's input source that took over ("" before)."""

    #: the period's inputs (input, effect, command, wall-clock s), drained by the input sink
    records: list[tuple[Input, str, tuple[float, float], float]]


class AuthorityRecorder:
    """A sink writing who drove each period on ``/lfd/authority`` (runs with a network)."""

    def __init__(self, log: LogWriter, session: Recorded) -> None:
        self.log, self.session = log, session
        log.add_topic(lfd.Authority.TOPIC, lfd.Authority.SCHEMA)

    def record(self, obs: Observation, command: tuple[float, float]) -> None:
        s = self.session
        self.log.write_raw(
            lfd.Authority.TOPIC, obs.t_ns, lfd.encode_authority(obs.t_ns, s.authority, s.authority_source)
        )


class InputRecorder:
    """A sink writing the session's inputs of each period on ``/teleop/input``."""

    def __init__(self, log: LogWriter, session: Recorded) -> None:
        self.log, self.session = log, session
        log.add_topic(TOPIC, SCHEMA)

    def record(self, obs: Observation, command: tuple[float, float]) -> None:
        for inp, effect, cmd, wall in self.session.records:
            self.log.write(
                TOPIC, obs.t_ns, teleop_input(obs.t_ns, inp, effect=effect, command=cmd, wall_s=wall)
            )
        self.session.records.clear()
