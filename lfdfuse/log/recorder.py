"""Recording a closed-loop run: the raw channels of DESIGN §5 at every tick, and provenance.

:class:`Recorder` is a :class:`~lfdfuse.sim.loop.Sink`: simulate, teleop and execute hand it to
the one loop, so every recorded run has the same channels written the same way.
"""

from __future__ import annotations

from lfdfuse import __version__
from lfdfuse.log import messages as msg
from lfdfuse.log.writer import LogWriter
from lfdfuse.robot.readings import Observation
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.world.parse import World


def provenance(
    *, command: str, seed: int, world: World, sensors: SensorParams, dt_s: float = 0.1, **extra: str
) -> dict[str, str]:
    """The ``lfdfuse`` metadata record of a recorded run (tool, command, seed, world, sensors)."""
    meta = {
        "tool": "lfdfuse",
        "version": __version__,
        "command": command,
        "seed": str(seed),
        "world": world.name,
        "laser_max_range_m": repr(sensors.laser.max_range_m),
        "sonar_max_range_m": repr(sensors.sonar.max_range_m),
        "camera_reach_m": repr(sensors.camera.reach_m),
        "dt_s": repr(dt_s),
    }
    meta.update(extra)
    return meta


class Recorder:
    """Writes ``/scan``, ``/sonar``, ``/pose``, ``/tf``, ``/targets`` and ``/cmd_vel`` of every tick."""

    def __init__(self, log: LogWriter, *, world: World, sensors: SensorParams) -> None:
        self.log = log
        self.laser = sensors.laser.geometry
        self.sonar = sensors.sonar.geometry
        log.attach("world.yaml", "application/yaml", world.source.encode())
        log.write("/world", 0, msg.world_scene(0, world))

    def record(self, obs: Observation, command: tuple[float, float]) -> None:
        log, t_ns, pose, reading = self.log, obs.t_ns, obs.pose, obs.reading
        log.write("/scan", t_ns, msg.laser_scan(t_ns, reading.ranges_m, self.laser))
        log.write("/sonar", t_ns, msg.laser_scan(t_ns, reading.sonar_m, self.sonar))
        log.write("/pose", t_ns, msg.pose_in_frame(t_ns, pose.x, pose.y, pose.theta))
        log.write("/tf", t_ns, msg.frame_transform(t_ns, pose.x, pose.y, pose.theta))
        log.write("/targets", t_ns, msg.target_detections(t_ns, reading.detections))
        log.write("/cmd_vel", t_ns, msg.twist(t_ns, command[0], command[1]))
