"""The Foxglove WebSocket transport of ``drive`` (``foxglove.websocket.v1`` / ``foxglove.sdk.v1``).

* :mod:`~lfdfuse.drive.foxglove.wire` — the protocol's frames, pure encode/decode;
* :mod:`~lfdfuse.drive.foxglove.channels` — which advertised channels to subscribe to, for which role;
* :mod:`~lfdfuse.drive.foxglove.client` — the transport: connect, subscribe, advertise, send.
"""
