"""The robot every stage shares: its pose, what it senses, where its laser sits, and ROS.

The types a simulator produces, an importer reads from a log, the behaviours compute from and
a live run decodes off the wire live here, below all of them: :mod:`~lfdfuse.robot.pose`
(where the robot is), :mod:`~lfdfuse.robot.records` (time-stamped scans, commands and poses
in the sensor's own frame, as a log or a wire carries them), :mod:`~lfdfuse.robot.readings`
(the base-frame scan layout and what the robot senses at one instant),
:mod:`~lfdfuse.robot.mount` (where the laser sits, and its scans turned into the base frame),
:mod:`~lfdfuse.robot.ros` (ROS messages into those records: tf, quaternions, LaserScan,
Odometry, Twist) and :mod:`~lfdfuse.robot.limits` (the speed limits a provenance states).
Nothing here reads a file, opens a socket or knows a stage.
"""
