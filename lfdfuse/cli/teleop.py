"""``lfdfuse teleop``: the terminal shell around :mod:`lfdfuse.sources.teleop`.

This module owns everything that touches the terminal: raw key input (restored on every exit
path), the live rich view, the Foxglove URL. The session, the key mapping and the server are
library code and know nothing of terminals.
"""

from __future__ import annotations

import os
import select
import sys
import tempfile
import termios
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from enum import StrEnum
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.console import Group
from rich.live import Live
from rich.panel import Panel
from rich.text import Text

from lfdfuse.cli.app import WORLD_HELP, app
from lfdfuse.cli.common import (
    check_outputs,
    console,
    duration_option,
    existing,
    finite,
    progress_bar,
    seed_option,
    start_option,
    user_errors,
)
from lfdfuse.cli.render import print_report, print_run
from lfdfuse.errors import ConfigError
from lfdfuse.estimate.methods import EstimateOptions
from lfdfuse.execute.correct import correct, correction_driver
from lfdfuse.execute.report import write_report
from lfdfuse.learn import LearnOptions, correction_lesson
from lfdfuse.network.stepper import NetworkStepper
from lfdfuse.network.table import FusionTable, load_table, write_table
from lfdfuse.robot.pose import Pose
from lfdfuse.robot.readings import ScanGeometry
from lfdfuse.sources.teleop.clock import SimClock
from lfdfuse.sources.teleop.inputs import Input
from lfdfuse.sources.teleop.keys import HELP, KeyDecoder
from lfdfuse.sources.teleop.script import ScriptInput, load_script
from lfdfuse.sources.teleop.session import (
    HANDBACK_KEY,
    TeleopOptions,
    TeleopSession,
    make_session,
    stop_on_signals,
    teleop,
)
from lfdfuse.sources.teleop.view import ARROWS, LASER, TRAIL, WALL, render_map
from lfdfuse.words import counted
from lfdfuse.world.model import DEFAULT_WORLD, World, load_world


class InputKind(StrEnum):
    """``--input``: who drives."""

    #: this terminal's keys
    KEYBOARD = "keyboard"
    #: a Foxglove client's Teleop panel over WebSocket
    FOXGLOVE = "foxglove"
    #: timed inputs from ``--script``, faster than real time
    SCRIPT = "script"


LAYOUT = "foxglove/teleop-layout.json"
#: a correction run without --duration ends when execute's would (its --max-time default)
TABLE_DURATION_S = 300.0


@app.command("teleop")
@user_errors
def teleop_cmd(
    world: str = typer.Option(DEFAULT_WORLD, "--world", "-w", help=WORLD_HELP),
    input_: InputKind = typer.Option(
        InputKind.KEYBOARD,
        "--input",
        "-i",
        help="keyboard (this terminal), foxglove (a Foxglove client's Teleop panel), or script (--script).",
    ),
    port: int = typer.Option(
        8765, "--port", min=0, max=65535, help="Foxglove WebSocket port (0: any free port)."
    ),
    host: str = typer.Option(
        "127.0.0.1", "--host", help="Foxglove server address (0.0.0.0: all interfaces)."
    ),
    script: Path | None = typer.Option(
        None, "--script", help="Timed inputs (YAML or CSV) for --input script; runs faster than real time."
    ),
    duration: float | None = duration_option(
        None, "--duration", "-d", help="Stop after this many seconds of wall-clock time (default: no limit)."
    ),
    timeout: float = typer.Option(
        2.5,
        "--timeout",
        min=0.1,  # one control period: a shorter timeout would stop every command
        callback=finite,
        help="Foxglove: stop the robot when no client command came for this many seconds.",
    ),
    seed: int = seed_option("Seed of every random draw (sensor noise)."),
    start: str | None = start_option(),
    out: Path = typer.Option(Path("demo.mcap"), "--out", "-o", help="Output MCAP file."),
    table: Path | None = typer.Option(
        None,
        "--table",
        help="A fusion table that drives until you take over (any key or client Twist); h gives control back.",
    ),
    handback: float | None = duration_option(
        None,
        "--handback",
        help="With --table: give control back to the network after this many seconds without input.",
    ),
    report: Path | None = typer.Option(
        None, "--report", help="With --table: write execute's JSON report of the network's task here."
    ),
    demos: list[Path] = typer.Option(
        [],
        "--demo",
        help="With --table: a segmented demo the table was learned from (repeat for several); after the"
        " run, the estimate with the correction is made and each step it adds or re-weights is listed.",
    ),
    estimate_to: Path | None = typer.Option(
        None, "--estimate-to", help="With --demo: write that estimate (the corrected table) here."
    ),
) -> None:
    """Drive the simulated robot yourself and record the run as a demonstration.

    Keyboard (default): keys as in ROS teleop_twist_keyboard — i forward, , back, j/l turn,
    u/o forward arcs, m/. back arcs, k or space stop, arrows too, q/z speed ±10%. A command
    holds until the next key. Esc or Ctrl-C ends the run and saves it.

    Foxglove: open the printed URL, load the layout lfdfuse/foxglove/teleop-layout.json and
    drive with its Teleop panel (it publishes geometry_msgs/Twist on /cmd_vel). Ctrl-C ends.

    The demo has the channels of `simulate` plus /teleop/input, provenance teacher: human;
    `segment`, `estimate` and `execute` take it unchanged. It is written when the run ends
    (key, --duration, SIGINT, SIGTERM), atomically; ending a run is not an error (exit 0).

    Corrections (--table): the learned network drives; any key or client Twist takes over at
    once, h (a script's {t: …, handback: true}, or --handback SECONDS without input) gives
    control back. The log adds who drove each tick (/lfd/authority) and the network's proposal
    (/lfd/step, /lfd/fused, help requests on /lfd/network). The run ends when the task is
    complete, or after --duration (default 300 s, as execute's --max-time). With --input script
    it is tick for tick the `execute` run of the same table, --seed and --start until the
    first input. With --demo (the table's demos), the estimate with the correction follows the
    session and lists per step what it adds or re-weights (--estimate-to writes that table).

    Examples:
      lfdfuse teleop --world building -o mine.mcap
      lfdfuse teleop --input foxglove --port 8765 --duration 600 -o mine.mcap
      lfdfuse teleop --input script --script drive.yaml -o scripted.mcap
      lfdfuse teleop --table t.yaml --input script --script fix.yaml -o fix.mcap
      lfdfuse teleop --table t.yaml --demo d.seg.mcap --estimate-to t2.yaml
    """
    if (input_ is InputKind.SCRIPT) != (script is not None):
        raise ConfigError("--script FILE goes with --input script (and only with it)")
    if table is None and (handback is not None or report is not None or demos):
        raise ConfigError("--handback, --report and --demo go with --table (a network to correct)")
    if estimate_to is not None and not demos:
        raise ConfigError("--estimate-to needs the demos the table was learned from (--demo)")
    check_outputs([out, report, estimate_to], [table, script, existing(world), *demos])
    w = load_world(world)
    tab = load_table(table) if table is not None else None
    if tab is not None and duration is None:
        duration = TABLE_DURATION_S
    pose = Pose.parse(start) if start else None
    opts = TeleopOptions(
        world=w,
        input_name=input_.value if script is None else f"script:{script.name}",
        seed=seed,
        start=pose,
        duration_s=duration,
        twist_timeout_s=timeout if input_ is InputKind.FOXGLOVE else None,
        handback_s=handback,
    )
    laser = opts.sensors.laser.geometry
    driver = correction_driver(opts, tab) if tab is not None else None
    result: Any = None

    def drive(session: TeleopSession, sinks: tuple[Any, ...] = ()) -> Any:
        nonlocal result
        if driver is None:
            return teleop(opts, session=session, out=out, sinks=sinks)
        assert table is not None
        result = correct(opts, session=session, driver=driver, table_name=table.name, out=out, sinks=sinks)
        return result.teleop

    def status(session: TeleopSession, extra: Any = None) -> Any:
        """The live view's status line: the clients, and with a table who drives and help."""
        if driver is None:
            return extra
        return lambda: "  ".join(p for p in (_network_status(session, driver), extra() if extra else "") if p)

    help_text = HELP + (
        f"\n{HANDBACK_KEY}      hand control back to the network" if driver is not None else ""
    )
    if input_ is InputKind.SCRIPT:
        assert script is not None
        feed = ScriptInput(load_script(script), end_with_last=driver is None)
        session = make_session(opts, inputs=[feed], clock=SimClock(), network=driver)
        with stop_on_signals(session):
            summary = drive(session)
    elif input_ is InputKind.FOXGLOVE:
        from lfdfuse.sources.teleop.foxglove_server import FoxgloveLive

        with FoxgloveLive(world=w, sensors=opts.sensors, host=host, port=port) as live:
            console.print(f"Foxglove server at [bold]{live.url}[/bold]", soft_wrap=True)
            console.print(f"  open {live.app_url()}", soft_wrap=True, markup=False)
            console.print(
                f"  or in Foxglove: Open connection → Foxglove WebSocket → {live.url}", soft_wrap=True
            )
            console.print(
                f"  layout: Layouts → Import from file… → {layout_path()}", soft_wrap=True, markup=False
            )
            session = make_session(opts, inputs=[live], network=driver)
            with (
                stop_on_signals(session),
                live_view(session, w, laser, status=status(session, lambda: _clients(live)), reserve=5),
            ):
                summary = drive(session, (live,))
            console.print(f"  published {live.published} live messages")
    else:
        if not sys.stdin.isatty():
            raise ConfigError(
                "--input keyboard needs a terminal on stdin; use --input foxglove or --input script"
            )
        fd = sys.stdin.fileno()
        keys = TerminalKeys(fd)
        session = make_session(opts, inputs=[keys], network=driver)
        with (
            stop_on_signals(session),
            raw_input_mode(fd),
            live_view(session, w, laser, help_text=help_text, status=status(session)),
        ):
            summary = drive(session)
    print_run(summary.run, title=f"teleop {w.name} / {opts.input_name}")
    console.print(f"  ended      {summary.ended} ({counted(summary.inputs, 'input')})")
    if result is not None:
        c = result.report["correction"]
        console.print(
            f"  corrected  the person drove {counted(c['person_ticks'], 'tick')}"
            f" ({counted(c['takeovers'], 'takeover')}, {counted(c['person_collisions'], 'collision')}),"
            f" the network {counted(c['network_ticks'], 'tick')}"
        )
        console.print("  while the network drove:")
        print_report(result.report, out=str(out))
        if report is not None:
            write_report(result.report, report)
        if demos and tab is not None:
            _lesson(tab, demos, out, estimate_to, seed)
        elif result.report["correction"]["person_ticks"]:
            console.print(
                "  (give --demo DEMO.seg.mcap, the table's demos, to see what this correction changes)"
            )
    console.print(f"next: lfdfuse segment {out}")


def _lesson(table: FusionTable, demos: list[Path], out: Path, estimate_to: Path | None, seed: int) -> None:
    """Estimate the table again with the correction just recorded; say what changed per step."""
    with tempfile.TemporaryDirectory() as tmp, progress_bar("estimate with the correction") as update:
        lesson = correction_lesson(
            table,
            demos=demos,
            correction=out,
            folder=Path(tmp),
            options=LearnOptions(EstimateOptions(seed=seed)),
            progress=update,
        )
    what = (
        f"written to {estimate_to}" if estimate_to is not None else "a dry run: --estimate-to FILE writes it"
    )
    console.print(f"estimated with {counted(len(demos), 'demo')} and this correction ({what}):")
    for line in lesson.changes or ("no step changes: the person drove nowhere the network learns from",):
        console.print(f"  {line}", markup=False, soft_wrap=True)
    for v in lesson.verdicts:
        console.print(f"  {v.describe()}", markup=False, soft_wrap=True)
    if lesson.checked is not None:
        console.print(f"  {lesson.checked.describe()}", markup=False, soft_wrap=True)
    if estimate_to is not None:
        write_table(lesson.table, estimate_to)


def layout_path() -> Path:
    """Where the shipped Foxglove layout is on this machine."""
    return Path(str(resources.files("lfdfuse") / LAYOUT))


def _network_status(session: TeleopSession, driver: NetworkStepper) -> str:
    """Who drives, the network's step, and its request for help when it has one."""
    dec = driver.last
    step = "-" if dec is None or dec.step is None else dec.step.name
    line = f"driving: {session.authority.upper()}  (network step {step})"
    ask = driver.asking
    if ask is not None:
        line += f"  NETWORK ASKS FOR HELP: step {ask.step}, BAC {ask.bac} ({ask.why})"
    return line


def _clients(live: Any) -> str:
    n = live.clients
    return f"{n} client{'s' if n != 1 else ''} connected at {live.url}"


class TerminalKeys:
    """An input source reading the keys typed since the last period from a raw-mode terminal."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.decoder = KeyDecoder()
        self.closed = False

    def poll(self, t_s: float) -> list[Input]:
        keys: list[str] = []
        got = False
        while not self.closed and select.select([self.fd], [], [], 0)[0]:
            data = os.read(self.fd, 1024)
            if not data:
                self.closed = True
                return [Input("end", "terminal closed", "keyboard")]
            got = True
            keys += self.decoder.feed(data)
        if not got:
            keys += self.decoder.flush()  # quiet for a period: a lone ESC is the Esc key
        return [Input("key", k, "keyboard") for k in keys]


@contextmanager
def raw_input_mode(fd: int) -> Iterator[None]:
    """Keys arrive one by one, unechoed, Ctrl-C as a byte; output stays cooked (rich draws as
    usual). The old settings come back in ``finally``: on return, exception, or signal."""
    saved = termios.tcgetattr(fd)
    mode = termios.tcgetattr(fd)
    mode[0] &= ~(termios.BRKINT | termios.ICRNL | termios.INPCK | termios.ISTRIP | termios.IXON)
    mode[3] &= ~(termios.ECHO | termios.ICANON | termios.IEXTEN | termios.ISIG)
    mode[6][termios.VMIN] = 1
    mode[6][termios.VTIME] = 0
    termios.tcsetattr(fd, termios.TCSADRAIN, mode)
    try:
        yield
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)


def live_view(
    session: TeleopSession,
    world: World,
    laser: ScanGeometry,
    *,
    help_text: str = "",
    status: Any = None,
    reserve: int = 0,
) -> Any:
    """A rich Live view refreshed 10 times a second, or nothing when stdout is not a terminal."""
    if not console.is_terminal:
        return nullcontext()
    trail: deque[tuple[float, float]] = deque(maxlen=2000)
    colors = {t.name[:1].upper(): _color(t.color) for t in world.targets}

    def render() -> Any:
        snap = session.snapshot
        width, height = console.size
        if snap is None:
            return Text("starting…")
        if not trail or trail[-1] != (snap.pose.x, snap.pose.y):
            trail.append((snap.pose.x, snap.pose.y))
        extra = help_text.count("\n") + 1 if help_text else 1
        rows = max(6, height - 5 - extra - reserve)  # reserve: lines printed above to keep in sight
        lines = render_map(
            world, snap.pose, snap.ranges_m, laser, cols=max(20, width - 2), rows=rows, trail=np.array(trail)
        )
        grid = Text("\n".join(lines))
        _style(grid, lines, colors)
        v, w = snap.command
        goals = ", ".join(f"{n} at {t:.1f} s" for n, t in snap.reached) or "none yet"
        info = Text.assemble(
            (f"t {snap.wall_s:6.1f} s", "bold"),
            f"  v {v:+.2f} m/s  ω {w:+.2f} rad/s",
            f"  (speed {snap.keys.speed_mps:.2f}, turn {snap.keys.turn_rps:.2f})" if help_text else "",
            f"  collisions {snap.collisions}",
            "\n",
            ("goals ", "bold"),
            goals,
            f"  last input: {snap.last_input or '-'}",
            f"  {status()}" if status else "",
            no_wrap=True,
            overflow="ellipsis",
        )
        parts: list[Any] = [Panel(grid, padding=0, title=f"lfdfuse teleop — {world.name}"), info]
        if help_text:
            parts.append(Text(help_text, style="dim", no_wrap=True, overflow="ellipsis"))
        return Group(*parts)

    return Live(console=console, get_renderable=render, refresh_per_second=10, transient=False)


def _style(text: Text, lines: list[str], colors: dict[str, str]) -> None:
    """Colour walls, laser, trail, targets and robot: one span per run of equal characters."""
    styles = {WALL: "grey50", LASER: "red", TRAIL: "cyan", **{a: "bold yellow" for a in ARROWS}, **colors}
    offset = 0
    for line in lines:
        j = 0
        while j < len(line):
            k = j + 1
            while k < len(line) and line[k] == line[j]:
                k += 1
            style = styles.get(line[j])
            if style:
                text.stylize(style, offset + j, offset + k)
            j = k
        offset += len(line) + 1


def _color(rgb: tuple[float, float, float]) -> str:
    r, g, b = (int(round(255 * c)) for c in rgb)
    return f"bold #{r:02x}{g:02x}{b:02x}"
