"""``lfdfuse drive``: the learned behaviour network on a live robot (DESIGN §15).

One module per job, data flowing down this list:

* :mod:`~lfdfuse.drive.wire` — the Foxglove WebSocket protocol's frames, pure encode/decode;
* :mod:`~lfdfuse.drive.channels` — which advertised channels to subscribe to, for which role;
* :mod:`~lfdfuse.drive.decode` — CDR (``ros2msg`` schemas, ``rosbags``) and lfdfuse's own JSON
  into our small records, and the ``geometry_msgs/msg/Twist`` we send;
* :mod:`~lfdfuse.drive.frames` — the laser mounting from tf, the scan in the base frame;
* :mod:`~lfdfuse.drive.safety` — the clamp and the stale-scan watchdog;
* :mod:`~lfdfuse.drive.core` — the control core: a scan in, a command out (no socket, no clock);
* :mod:`~lfdfuse.drive.record` — the live MCAP;
* :mod:`~lfdfuse.drive.options` — what a session is asked and what it answers;
* :mod:`~lfdfuse.drive.session` — the socket shell: connect, reconnect, signals, duration.
"""
