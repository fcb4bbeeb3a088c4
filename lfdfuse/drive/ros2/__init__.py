"""The ROS 2 transport of ``drive`` and ``record`` (``--ros2``): DDS through ``cyclonedds``, no ROS install.

* :mod:`~lfdfuse.drive.ros2.names` — ROS 2's names and QoS on DDS: the topic of each role, its
  type, the QoS a ROS 2 publisher uses, the domain;
* :mod:`~lfdfuse.drive.ros2.client` — the transport: a participant, readers and the command writer.

Only :mod:`lfdfuse.drive.session` names this package, and only when ``--ros2`` is asked: the
default path never imports ``cyclonedds``.
"""
