"""``cyclonedds`` loads only on the ``--ros2`` path: ``--help``, a command's help and ``inspect``
never import it; the transport of a ``ros2://`` URL does."""

from __future__ import annotations

import subprocess
import sys

from tests.conftest import ROOT

# runs the CLI in-process, one command after another, and reports after each whether
# cyclonedds is loaded (one interpreter: four fresh ones would cost seconds each)
_RUN = """
import sys
from typer.testing import CliRunner
from lfdfuse.cli.main import app
for args in sys.argv[1:]:
    res = CliRunner().invoke(app, args.split("|"))
    print(res.exit_code, "cyclonedds" in sys.modules)
from lfdfuse.drive.session import TRANSPORTS
from lfdfuse.drive.transport import Topics
TRANSPORTS["ros2"]("ros2://domain/7", Topics())
print(0, "cyclonedds" in sys.modules)
"""


def test_help_and_inspect_do_not_import_cyclonedds() -> None:
    sample = ROOT / "sample_logs" / "keep-left-building.mcap"
    commands = ["--help", "drive|--help", "record|--help", f"inspect|{sample}"]
    res = subprocess.run(
        [sys.executable, "-c", _RUN, *commands], capture_output=True, text=True, cwd=ROOT, timeout=300
    )
    assert res.returncode == 0, res.stderr
    # none of the commands loads it; the transport of a ros2:// URL does (the check can see it)
    assert res.stdout.split("\n")[:5] == ["0 False"] * 4 + ["0 True"], res.stdout + res.stderr
