"""Keyboard teleoperation as people know it from ROS ``teleop_twist_keyboard``: pure functions.

Two small pieces, both free of terminals and clocks so they can be tested byte by byte:

- :class:`KeyDecoder` turns the bytes a terminal in raw mode delivers into key names
  (``"i"``, ``"space"``, ``"up"``, ``"esc"``, ``"ctrl-c"``, …), arrow escape sequences
  included, even when a sequence arrives split over two reads;
- :func:`press` is the ``teleop_twist_keyboard`` state machine: a move key sets a direction
  that holds until the next key, ``q``/``z`` (``w``/``x`` speed only, ``e``/``c`` turn only)
  scale the speeds, ``k``, space and any other key stop, ``Esc`` and ``Ctrl-C`` end the run.

>>> s = KeyState()
>>> s = press(s, "i").state
>>> s.command
(0.4, 0.0)
>>> press(s, "z").state.command
(0.36, 0.0)
>>> press(s, "esc").quit
True
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from lfdfuse.control.command import DriveParams

#: key → (direction of linear.x, direction of angular.z), exactly ``teleop_twist_keyboard``'s
#: bindings (its ``.`` backs up turning counter-clockwise, ``m`` clockwise); arrows alike
MOVES: dict[str, tuple[int, int]] = {
    "i": (1, 0),
    "o": (1, -1),
    "j": (0, 1),
    "l": (0, -1),
    "u": (1, 1),
    ",": (-1, 0),
    ".": (-1, 1),
    "m": (-1, -1),
    "up": (1, 0),
    "down": (-1, 0),
    "left": (0, 1),
    "right": (0, -1),
}

#: key → (factor on speed, factor on turn)
SCALES: dict[str, tuple[float, float]] = {
    "q": (1.1, 1.1),
    "z": (0.9, 0.9),
    "w": (1.1, 1.0),
    "x": (0.9, 1.0),
    "e": (1.0, 1.1),
    "c": (1.0, 0.9),
}

STOPS = frozenset({"k", "space"})
QUITS = frozenset({"esc", "ctrl-c"})

HELP = (
    "u i o  forward arcs, forward     q/z  all speeds ±10% (w/x linear, e/c turn)\n"
    "j k l  turn left, stop, right    space stops too, arrow keys move\n"
    "m , .  back arcs, back           Esc or Ctrl-C ends the run and saves it"
)

_MIN_SPEED_MPS = 0.02
_MIN_TURN_RPS = 0.05


@dataclass(frozen=True)
class KeyState:
    """The held direction and the speed scales (m/s, rad/s) of a keyboard teleop."""

    x: int = 0  # -1, 0, +1: direction of linear.x
    th: int = 0  # -1, 0, +1: direction of angular.z (counter-clockwise positive)
    speed_mps: float = 0.4
    turn_rps: float = 1.0

    @property
    def command(self) -> tuple[float, float]:
        """The command ``(v m/s, ω rad/s)`` this state holds."""
        return round(self.x * self.speed_mps, 6) + 0.0, round(self.th * self.turn_rps, 6) + 0.0


@dataclass(frozen=True)
class KeyEffect:
    """What one key did: the new state, whether the run ends, and whether the key was bound."""

    state: KeyState
    quit: bool = False
    known: bool = True


def is_key_name(name: str) -> bool:
    """A key a keyboard can send: one printable character, or a named key (``up``, ``space``,
    ``esc``, ``enter`` …). An unbound key is still a key (it stops the robot); ``foo`` is not.

    >>> [is_key_name(k) for k in ("i", "up", "space", "esc", "a", "foo", "")]
    [True, True, True, True, True, False, False]
    """
    named = {*MOVES, *SCALES, *STOPS, *QUITS, *_CSI_FINAL.values(), *_NAMED.values()}
    return name in named or (len(name) == 1 and name.isprintable())


def press(state: KeyState, key: str, limits: DriveParams | None = None) -> KeyEffect:
    """Apply one key name to a state. Speeds stay within the robot's limits.

    Unbound keys stop the robot, as in ``teleop_twist_keyboard`` ("anything else: stop").
    """
    lim = limits or DriveParams()
    if key in QUITS:
        return KeyEffect(replace(state, x=0, th=0), quit=True)
    if key in MOVES:
        x, th = MOVES[key]
        return KeyEffect(replace(state, x=x, th=th))
    if key in SCALES:
        fs, ft = SCALES[key]
        # rounded so that repeated presses do not accumulate float noise; the limits exact
        speed = min(max(round(state.speed_mps * fs, 6), _MIN_SPEED_MPS), lim.v_max_mps)
        turn = min(max(round(state.turn_rps * ft, 6), _MIN_TURN_RPS), lim.omega_max_rps)
        return KeyEffect(replace(state, speed_mps=speed, turn_rps=turn))
    return KeyEffect(replace(state, x=0, th=0), known=key in STOPS)


_CSI_FINAL = {"A": "up", "B": "down", "C": "right", "D": "left"}
_NAMED = {0x03: "ctrl-c", 0x20: "space", 0x0D: "enter", 0x0A: "enter", 0x09: "tab", 0x7F: "backspace"}


class KeyDecoder:
    """Bytes from a raw-mode terminal → key names.

    Arrow keys arrive as ``ESC [ A`` (or ``ESC O A`` in application mode). A lone ``ESC`` is
    the Esc key only once no more bytes follow: :meth:`feed` keeps a trailing ``ESC`` pending
    and :meth:`flush` (called when the input has been quiet for a moment) releases it.

    >>> d = KeyDecoder()
    >>> d.feed(b"i\\x1b[Ak\\x1b")
    ['i', 'up', 'k']
    >>> d.feed(b"[D"), d.flush()
    (['left'], [])
    >>> d.feed(b"\\x1b"), d.flush()
    ([], ['esc'])
    """

    def __init__(self) -> None:
        self._pending = b""

    def feed(self, data: bytes) -> list[str]:
        buf = self._pending + data
        keys: list[str] = []
        i = 0
        while i < len(buf):
            b = buf[i]
            if b != 0x1B:
                keys.append(_byte_name(b))
                i += 1
                continue
            if i + 1 >= len(buf):
                break  # a lone ESC so far: wait for what follows
            intro = buf[i + 1]
            if intro not in (0x5B, 0x4F):  # not '[' or 'O': Esc, then an ordinary key
                keys.append("esc")
                i += 1
                continue
            j = i + 2
            if intro == 0x5B:  # CSI: parameter and intermediate bytes, then a final byte
                while j < len(buf) and 0x20 <= buf[j] <= 0x3F:
                    j += 1
            if j >= len(buf):
                break  # incomplete sequence: wait
            final = chr(buf[j])
            keys.append(_CSI_FINAL.get(final, "unknown"))
            i = j + 1
        self._pending = buf[i:]
        return keys

    def flush(self) -> list[str]:
        """The input went quiet: a pending ``ESC`` (or a cut-off sequence) is the Esc key."""
        pending, self._pending = self._pending, b""
        return ["esc"] if pending else []


def _byte_name(b: int) -> str:
    if b in _NAMED:
        return _NAMED[b]
    if 0x21 <= b <= 0x7E:
        return chr(b)
    if b < 0x20:
        return f"ctrl-{chr(b + 0x60)}"
    return "unknown"
