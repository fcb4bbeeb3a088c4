"""``lfdfuse drive``: the learned behaviour network on a live robot (DESIGN §15).

One module per job, data flowing down this list:

* :mod:`~lfdfuse.drive.transport` — the seam: a transport opens links, a link streams decoded
  records (role, record, arrival time) and sends commands;
* :mod:`~lfdfuse.drive.foxglove` — the Foxglove WebSocket transport (its frames, channels, client);
* :mod:`~lfdfuse.drive.ros2` — the ROS 2 transport over DDS (``--ros2``; ``cyclonedds``, loaded
  only on that path);
* :mod:`~lfdfuse.drive.decoders` — the registry: (encoding, schema) → role and decoder;
* :mod:`~lfdfuse.drive.decode` — CDR (``ros2msg`` schemas, ``rosbags``) and lfdfuse's own JSON
  into our small records, and the ``geometry_msgs/msg/Twist`` we send;
* :mod:`~lfdfuse.drive.frames` — the laser mounting from tf, the scan in the base frame;
* :mod:`~lfdfuse.drive.safety` — the clamp and the stale-scan watchdog;
* :mod:`~lfdfuse.drive.core` — the control core: a scan in, a command out (no socket, no clock);
* :mod:`~lfdfuse.drive.record` — the live MCAP;
* :mod:`~lfdfuse.drive.options` — what a session is asked and what it answers;
* :mod:`~lfdfuse.drive.lifecycle` — the run over any transport: signals, duration, reconnecting,
  the watchdog's zero Twists, latency, the summary;
* :mod:`~lfdfuse.drive.session` — the entry: the transport of the URL (``ws://``, ``ros2://``), then the run.

``lfdfuse record`` (:mod:`lfdfuse.record`, a floor above) listens through the same transports.
"""
