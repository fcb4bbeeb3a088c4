"""``teleop``: a person drives the simulated robot in real time (DESIGN §10).

:mod:`.keys` maps terminal keys to commands, :mod:`.inputs` holds what a person did and its
``/teleop/input`` message, :mod:`.script` replays timed inputs from a file,
:mod:`.foxglove_server` is the live Foxglove WebSocket side, :mod:`.session` the real-time
command source and the recorded run, on a :mod:`.clock` (the wall's, or a script's simulated
one), writing its own channels through :mod:`.record`.
"""
