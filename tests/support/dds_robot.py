"""A ROS 2 robot over DDS, in its own process: lfdfuse's simulator behind ROS 2's names, types and QoS.

``python -m tests.support.dds_robot --domain N --out result.json [...]`` joins DDS domain ``N``
as a participant named ``lfdfuse_test_robot`` and publishes what a ROS 2 robot publishes:
``rt/scan`` (``sensor_msgs::msg::dds_::LaserScan_``, best effort, in a ``laser`` frame that faces
the robot's left), ``rt/odom`` (``nav_msgs/Odometry``, best effort), ``rt/tf`` (reliable) and
``rt/tf_static`` (reliable, transient local: published once, latched); it drives by the
``geometry_msgs/Twist`` (``--cmd-stamped``: ``TwistStamped``) it reads on ``rt/cmd_vel``
(reliable). Stamps are the epoch time at the start plus the simulated time (``--lockstep``: plus
the wall time since the start, the robot's clock, as its steps are not 0.1 s apart).

Pacing: ``--lockstep`` steps as soon as a command answers a scan (a minute of robot time in
seconds, the same closed loop; with ``--speed``, no faster than that × real time); else the robot
runs at ``--speed`` × real time (default 1). ``--person STYLE``
adds a scripted person driving it with their own teleop: another participant
(``teleop_twist_keyboard``) that publishes the style teacher's Twist on ``rt/cmd_vel`` each tick.
Faults: ``--pause-at T --pause-for S`` (scans stop), ``--malformed-at T`` (samples on ``rt/scan``
that are no LaserScan: see :meth:`Robot.malformed`). On exit the participants are deleted, so
their peers see them leave at once (as a ROS 2 node that shuts down). One JSON line on stdout when it is listening
(``{"ready": true}``); on exit (its duration, SIGTERM) ``--out`` gets the poses, the commands
received (monotonic wall time, tick, v, ω), collisions and the fault marks.

Not part of the pipeline: a test rig (``tests/drive``, the ``drive`` benchmark).
"""

import argparse
import json
import math
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
from cyclonedds._clayer import ddspy_write
from cyclonedds.core import (
    InstanceState,
    Listener,
    Policy,
    Qos,
    ReadCondition,
    SampleState,
    ViewState,
    WaitSet,
)
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

from lfdfuse.control.command import DriveParams
from lfdfuse.robot import idl
from lfdfuse.robot.pose import Pose
from lfdfuse.sim.loop import side_beam_index
from lfdfuse.sim.sensors import SensorParams
from lfdfuse.sim.simulator import Simulator
from lfdfuse.sources.planner import Planner
from lfdfuse.sources.tasks import Leg, parse_style
from lfdfuse.sources.teachers import StyleTeacher
from lfdfuse.world.model import load_world

SENSOR = Qos(Policy.Reliability.BestEffort, Policy.Durability.Volatile, Policy.History.KeepLast(5))
RELIABLE = Qos(
    Policy.Reliability.Reliable(100_000_000), Policy.Durability.Volatile, Policy.History.KeepLast(100)
)
LATCHED = Qos(
    Policy.Reliability.Reliable(100_000_000), Policy.Durability.TransientLocal, Policy.History.KeepLast(1)
)
COMMAND = Qos(
    Policy.Reliability.Reliable(100_000_000), Policy.Durability.Volatile, Policy.History.KeepLast(10)
)
LASER_YAW = math.pi / 2  # the scanner faces the robot's left: only tf says so


def _named(name: str) -> Qos:
    return Qos(Policy.EntityName(name))


def _header(t_ns: int, frame: str) -> idl.Header:
    return idl.Header(idl.stamp(t_ns), frame)


def _quat(theta: float) -> idl.Quaternion:
    return idl.Quaternion(0.0, 0.0, math.sin(theta / 2), math.cos(theta / 2))


def _tf(t_ns: int, parent: str, child: str, x: float, y: float, theta: float) -> idl.TransformStamped:
    return idl.TransformStamped(
        _header(t_ns, parent), child, idl.Transform(idl.Vector3(x, y, 0.0), _quat(theta))
    )


class Robot:
    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.world = load_world(args.world)
        self.sensors = SensorParams()
        self.drive = DriveParams()
        self.sim = Simulator(self.world, np.random.default_rng(args.seed), self.sensors)
        self.dp = DomainParticipant(args.domain, qos=_named("lfdfuse_test_robot"))
        self.listened = threading.Event()  # a reader of the scan is matched
        on_scan = Listener()  # type: ignore[no-untyped-call]
        on_scan.set_on_publication_matched(
            lambda w, st: self.listened.set() if st.current_count > 0 else self.listened.clear()
        )
        self.w_scan = DataWriter(
            self.dp, Topic(self.dp, "rt/scan", idl.LaserScan), qos=SENSOR, listener=on_scan
        )
        self.w_odom = DataWriter(self.dp, Topic(self.dp, "rt/odom", idl.Odometry), qos=SENSOR)
        self.w_tf = DataWriter(self.dp, Topic(self.dp, "rt/tf", idl.TFMessage), qos=RELIABLE)
        self.w_static = DataWriter(self.dp, Topic(self.dp, "rt/tf_static", idl.TFMessage), qos=LATCHED)
        cmd_type = idl.TwistStamped if args.cmd_stamped else idl.Twist
        self.matched = threading.Event()
        # no data listener on the command reader: the person's writer lives in this process, and a
        # Python listener on a locally written topic can deadlock the binding (see _take)
        listener = Listener()  # type: ignore[no-untyped-call]
        listener.set_on_subscription_matched(
            lambda r, st: self.matched.set() if st.current_count > 0 else self.matched.clear()
        )
        self.r_cmd = DataReader(
            self.dp, Topic(self.dp, "rt/cmd_vel", cmd_type), qos=COMMAND, listener=listener
        )
        self.waitset = WaitSet(self.dp)
        self.waitset.attach(ReadCondition(self.r_cmd, SampleState.Any | ViewState.Any | InstanceState.Any))
        self.person: StyleTeacher | None = None
        if args.person:
            self.tp = DomainParticipant(args.domain, qos=_named("teleop_twist_keyboard"))
            self.w_person = DataWriter(self.tp, Topic(self.tp, "rt/cmd_vel", idl.Twist), qos=COMMAND)
            self.person = StyleTeacher(
                world=self.world,
                legs=[Leg(None, parse_style(args.person))],
                planner=Planner(self.world, robot_radius_m=0.25),
                geometry=self.sensors.laser.geometry,
                camera=self.sensors.camera,
                drive=self.drive,
                rng=np.random.default_rng(args.seed + 1),
            )
        self.stop = threading.Event()
        self.received: list[tuple[float, int, float, float]] = []
        self.published: list[float] = []  # wall time of each scan published
        self.poses: list[tuple[float, float, float]] = []
        self.sides: list[tuple[float, float]] = []
        self.marks: dict[str, float] = {}
        self.tick = 0
        self.t0_ns = time.time_ns() // 1_000_000_000 * 1_000_000_000
        self.t0_wall = time.monotonic()

    def publish(self, t_ns: int, pose: Pose, ranges: np.ndarray, *, scan: bool) -> None:
        stamp = self.t0_ns + t_ns
        if (
            self.args.lockstep
        ):  # stamped by the robot's clock, as a real robot's are (its steps are not 0.1 s apart)
            stamp = self.t0_ns + round((time.monotonic() - self.t0_wall) * 1e9)
        cov = [0.0] * 36
        odom = idl.Odometry(
            _header(stamp, "odom"),
            "base_link",
            idl.PoseWithCovariance(idl.PoseMsg(idl.Point(pose.x, pose.y, 0.0), _quat(pose.theta)), cov),
            idl.TwistWithCovariance(idl.Twist(), cov),
        )
        self.w_odom.write(odom)
        self.w_tf.write(idl.TFMessage([_tf(stamp, "odom", "base_link", pose.x, pose.y, pose.theta)]))
        if scan:
            g = self.sensors.laser.geometry
            start = g.start_rad - LASER_YAW
            msg = idl.LaserScan(
                _header(stamp, "laser"),
                start,
                start + g.increment_rad * (g.count - 1),
                g.increment_rad,
                0.0,
                0.1,
                0.05,
                g.max_range_m,
                [float(r) for r in ranges],
                [],
            )
            self.w_scan.write(msg)
            self.published.append(time.monotonic())

    def malformed(self, stamp_ns: int) -> None:
        """Three byte strings that are no CDR LaserScan (Cyclone DDS drops them on receipt: it
        checks every sample against the type), then three well-formed LaserScans that are no scan
        (no beams, a NaN increment)."""
        for _ in range(3):
            ddspy_write(self.w_scan._ref, b"\x00\x01\x00\x00\x07\x00\x00\x00 not a LaserScan")
        time.sleep(0.1)  # sent apart: a packet with a sample that does not deserialise is dropped whole
        for k in range(3):
            bad = idl.LaserScan(
                _header(stamp_ns + k, "laser"), 0.0, 0.0, math.nan, 0.0, 0.1, 0.05, 8.0, [], []
            )
            self.w_scan.write(bad)

    def _take(self, timeout_s: float) -> list[tuple[float, float, float]]:
        """The commands that came, waiting up to ``timeout_s`` for the first (a wait set: the
        wait releases the GIL, and no Python listener runs on a DDS thread)."""
        end = time.monotonic() + max(timeout_s, 0.0)
        while True:
            got = []
            for m in self.r_cmd.take(N=64):
                if not isinstance(m, idl.Twist | idl.TwistStamped):
                    continue  # a writer left (an invalid sample: no data)
                tw = m.twist if isinstance(m, idl.TwistStamped) else m
                got.append((time.monotonic(), float(tw.linear.x), float(tw.angular.z)))
            left = end - time.monotonic()
            if got or left <= 0:
                return got
            self.waitset.wait(round(min(left, 0.05) * 1e9))

    def run(self) -> None:
        a = self.args
        self.w_static.write(idl.TFMessage([_tf(self.t0_ns, "base_link", "laser", 0.1, 0.0, LASER_YAW)]))
        if a.wait_for_driver and not self._wait(self.matched, 30.0):
            return
        if a.wait_for_listener and not self._wait(self.listened, 30.0):
            return
        dt = self.sim.robot.dt_s
        start = Pose(*(float(v) for v in a.start.split(","))) if a.start else None
        obs = self.sim.reset(start)
        angles = self.sensors.laser.geometry.angles
        i_left, i_right = side_beam_index(angles, math.pi / 2), side_beam_index(angles, -math.pi / 2)
        cmd = (0.0, 0.0)
        t_next = time.monotonic()
        begin = time.monotonic()
        for _ in range(int(round(a.seconds / dt))):
            if self.stop.is_set():
                break
            sim_s = obs.t_ns / 1e9
            paused = a.pause_at is not None and a.pause_at <= sim_s < a.pause_at + a.pause_for
            if paused and "pause" not in self.marks:
                self.marks["pause"] = time.monotonic()
            if not paused and "pause" in self.marks and "back" not in self.marks:
                self.marks["back"] = time.monotonic()
            if a.malformed_at is not None and sim_s >= a.malformed_at and "bad" not in self.marks:
                self.malformed(self.t0_ns + obs.t_ns)
                self.marks["bad"] = time.monotonic()
            self.poses.append(obs.pose.as_tuple())
            self.sides.append((float(obs.reading.ranges_m[i_left]), float(obs.reading.ranges_m[i_right])))
            self.publish(obs.t_ns, obs.pose, obs.reading.ranges_m, scan=not paused)
            if self.person is not None:
                v, w = self.person.command(obs)
                self.w_person.write(idl.Twist(idl.Vector3(v, 0.0, 0.0), idl.Vector3(0.0, 0.0, w)))
            if (a.lockstep or self.person is not None) and not paused:
                got = self._take(a.command_timeout)
                if a.speed is not None:  # no faster than --speed × real time
                    t_next += dt / a.speed
                    time.sleep(max(0.0, t_next - time.monotonic()))
            else:
                t_next += dt / (a.speed or 1.0)
                got = self._take(t_next - time.monotonic())
                time.sleep(max(0.0, t_next - time.monotonic()))
            for wall, v, w in got:
                self.received.append((wall, self.tick, v, w))
                cmd = (v, w)
            obs = self.sim.step(*cmd)
            self.tick += 1
        self.marks["end"] = time.monotonic()
        self.marks["wall_s"] = time.monotonic() - begin

    def _wait(self, ev: threading.Event, timeout_s: float) -> bool:
        end = time.monotonic() + timeout_s
        while not ev.wait(0.02):
            if self.stop.is_set() or time.monotonic() > end:
                return False
        return True

    def close(self) -> None:
        """Leave the domain now (peers see the participants go, rather than their lease expire)."""
        for dp in (getattr(self, "tp", None), self.dp):
            if dp is not None:
                dp.__del__()

    def result(self) -> dict[str, Any]:
        return {
            "poses": self.poses,
            "sides": self.sides,
            "received": self.received,
            "published": self.published,
            "collisions": self.sim.collisions,
            "marks": self.marks,
            "ticks": self.tick,
        }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description="A simulated ROS 2 robot over DDS (a test rig).")
    ap.add_argument("--domain", type=int, required=True)
    ap.add_argument("--world", default="tee")
    ap.add_argument("--start", default="")
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--lockstep", action="store_true")
    ap.add_argument("--speed", type=float, default=None)
    ap.add_argument("--command-timeout", type=float, default=1.0)
    ap.add_argument("--wait-for-driver", action="store_true", help="start once a command writer is matched")
    ap.add_argument("--wait-for-listener", action="store_true", help="start once a scan reader is matched")
    ap.add_argument("--person", default="")
    ap.add_argument("--cmd-stamped", action="store_true")
    ap.add_argument("--pause-at", type=float, default=None)
    ap.add_argument("--pause-for", type=float, default=1.5)
    ap.add_argument("--malformed-at", type=float, default=None)
    ap.add_argument("--out", default="")
    args = ap.parse_args(argv)
    robot = Robot(args)
    signal.signal(signal.SIGTERM, lambda *_: robot.stop.set())
    sys.stdout.write(json.dumps({"ready": True}) + "\n")
    sys.stdout.flush()
    try:
        robot.run()
    finally:
        if args.out:
            Path(args.out).write_text(json.dumps(robot.result()))
        robot.close()


if __name__ == "__main__":
    main()
