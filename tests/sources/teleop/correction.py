"""A correction log for tests (of this stage and of segment/estimate pooling): a known table
drives the corridor, a scripted person takes over for a while, then hands back.

``correction_log(tmp)`` writes it and returns its path and the ticks (ns) the person drove.
"""

from __future__ import annotations

from pathlib import Path

from lfdfuse.execute.correct import correct, correction_driver
from lfdfuse.network.table import load_table
from lfdfuse.sources.teleop.clock import SimClock
from lfdfuse.sources.teleop.inputs import Input
from lfdfuse.sources.teleop.script import ScriptInput, parse_yaml
from lfdfuse.sources.teleop.session import TeleopOptions, make_session
from lfdfuse.world.model import load_world
from tests.conftest import ROOT

CORRIDOR_TABLE = ROOT / "lfdfuse" / "evaluate" / "truths" / "corridor-center.yaml"

#: the person steers toward the left wall and follows it, then gives control back
CORRECTION_SCRIPT = [
    {"t": 4.0, "key": "u"},
    {"t": 5.0, "key": "i"},
    {"t": 6.5, "key": "o"},
    {"t": 7.0, "key": "i"},
    {"t": 9.0, "handback": True},
]


class Fed:
    """An input source fed by hand: ``at[t_s]`` lists the inputs arriving at that time."""

    def __init__(self, at: dict[float, list[Input]]) -> None:
        self.at = dict(at)

    def poll(self, t_s: float) -> list[Input]:
        due = [t for t in self.at if t <= t_s + 1e-9]
        return [i for t in sorted(due) for i in self.at.pop(t)]


def correction_log(tmp: Path, *, seed: int = 0, duration_s: float = 14.0) -> tuple[Path, list[int]]:
    """Write ``tmp/correction.mcap`` (``teleop --table`` with the corridor table and the script
    above); returns the path and the sorted stamps (ns) of the ticks the person drove."""
    opts = TeleopOptions(
        world=load_world("corridor"), input_name="script:fix.yaml", seed=seed, duration_s=duration_s
    )
    driver = correction_driver(opts, load_table(CORRIDOR_TABLE))
    feed = ScriptInput(parse_yaml(CORRECTION_SCRIPT), end_with_last=False)
    session = make_session(opts, inputs=[feed], clock=SimClock(), network=driver)
    out = tmp / "correction.mcap"
    correct(opts, session=session, driver=driver, table_name=CORRIDOR_TABLE.name, out=out)
    first, last = round(4.0 * 10), round(9.0 * 10)  # the person drives from 4.0 s until the handback
    return out, [k * 100_000_000 for k in range(first, last)]
