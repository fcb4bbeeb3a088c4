"""ROS 2 on DDS: which DDS topic, type and QoS each of ``drive``'s roles uses, and the domain.

A ROS 2 topic ``/scan`` is the DDS topic ``rt/scan``; a message ``sensor_msgs/msg/LaserScan`` the
type ``sensor_msgs::msg::dds_::LaserScan_`` (:mod:`lfdfuse.robot.idl`). The QoS are what ROS 2
publishers use, read from the side that must match them:

* ``--scan``, ``--odom``, ``/tf``, the robot's own ``--cmd`` (``--shadow``, ``record``): best-effort
  readers, which match a best-effort ("sensor data") and a reliable publisher alike;
* ``/tf_static``: a reliable, transient-local reader keeping the last 100 (what ``tf2``'s static
  listener asks), so the latched mounting arrives however late we join;
* our ``--cmd``: a reliable, volatile writer keeping the last 10 (ROS 2's default profile), which
  a robot's reliable or best-effort ``/cmd_vel`` subscriber accepts.

The network settings (interfaces, peers) are Cyclone DDS's own: ``CYCLONEDDS_URI``, as for a
ROS 2 node using ``rmw_cyclonedds``.
"""

from __future__ import annotations

from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.idl import IdlStruct
from cyclonedds.util import duration

from lfdfuse.drive.decode import Role
from lfdfuse.robot import idl

SENSOR = Qos(Policy.Reliability.BestEffort, Policy.Durability.Volatile, Policy.History.KeepLast(5))
LATCHED = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.Durability.TransientLocal,
    Policy.History.KeepLast(100),
)
COMMAND = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.Durability.Volatile,
    Policy.History.KeepLast(10),
)

BEST_EFFORT = "best effort, volatile"

#: QoS policy ids as Cyclone DDS reports them (``dds_qos_policy_id_t``), for a one-line note
POLICY_NAMES = {
    2: "durability",
    3: "presentation",
    4: "deadline",
    5: "latency budget",
    6: "ownership",
    8: "liveliness",
    10: "partition",
    11: "reliability",
    12: "destination order",
    21: "lifespan",
    22: "durability service",
    25: "data representation",
}
#: the policy id Cyclone DDS reports for a publisher of another type on the topic
TYPE_POLICY = 24


@dataclass(frozen=True)
class Wanted:
    """One topic a link reads: its role, ROS and DDS names, the struct and the reader's QoS."""

    role: Role
    topic: str
    dds: str
    struct: type[IdlStruct]
    qos: Qos
    qos_text: str  # the reader's QoS in words

    @property
    def type_name(self) -> str:
        return str(self.struct.__idl_typename__)


def wanted(*, scan: str, odom: str, cmd: str, listen_cmd: bool) -> tuple[Wanted, ...]:
    """The topics to read: the scan, odometry, tf, tf_static, and with ``listen_cmd`` the robot's
    own commands (a ``Twist``; :func:`command_struct` says when it is stamped)."""
    out = [
        Wanted(Role.SCAN, scan, idl.dds_topic(scan), idl.LaserScan, SENSOR, BEST_EFFORT),
        Wanted(Role.ODOM, odom, idl.dds_topic(odom), idl.Odometry, SENSOR, BEST_EFFORT),
        Wanted(Role.TF, "/tf", idl.dds_topic("/tf"), idl.TFMessage, SENSOR, BEST_EFFORT),
        Wanted(
            Role.TF,
            "/tf_static",
            idl.dds_topic("/tf_static"),
            idl.TFMessage,
            LATCHED,
            "reliable, transient local",
        ),
    ]
    if listen_cmd:
        out.append(Wanted(Role.CMD, cmd, idl.dds_topic(cmd), idl.Twist, SENSOR, BEST_EFFORT))
    return tuple(out)


def command_struct(type_names: set[str]) -> type[IdlStruct]:
    """The command's struct for a topic seen with ``type_names``: ``TwistStamped`` when the robot's
    topic has that type (ROS 2 Jazzy's Nav2, a TurtleBot 4), else ``Twist``."""
    return idl.TwistStamped if idl.TwistStamped.__idl_typename__ in type_names else idl.Twist
