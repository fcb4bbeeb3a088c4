"""``cyclonedds`` loads only on the ``--ros2`` path: ``--help``, a command's help and ``inspect``
never import it (nor does ``drive --connect``'s module graph), and ``drive --ros2`` does."""

from __future__ import annotations

import os
import subprocess
import sys

from tests.conftest import ROOT

# runs the CLI in-process, then reports whether cyclonedds was imported
_RUN = """
import sys
from typer.testing import CliRunner
from lfdfuse.cli.main import app
res = CliRunner().invoke(app, sys.argv[1:])
print(res.exit_code, "cyclonedds" in sys.modules)
"""


def _run(*args: str) -> str:
    res = subprocess.run(
        [sys.executable, "-c", _RUN, *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=dict(os.environ),
        timeout=300,
    )
    assert res.returncode == 0, res.stderr
    return res.stdout.strip().splitlines()[-1]


def test_help_and_inspect_do_not_import_cyclonedds() -> None:
    sample = ROOT / "sample_logs" / "keep-left-building.mcap"
    for args in (["--help"], ["drive", "--help"], ["record", "--help"], ["inspect", str(sample)]):
        assert _run(*args) == "0 False", args
    # and the check sees it where it belongs: the transport of a ros2:// URL
    code = (
        "import sys\n"
        "from lfdfuse.drive.session import TRANSPORTS\n"
        "from lfdfuse.drive.transport import Topics\n"
        "print(0, 'cyclonedds' in sys.modules)\n"
        "TRANSPORTS['ros2']('ros2://domain/7', Topics())\n"
        "print(0, 'cyclonedds' in sys.modules)\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert res.stdout.split() == ["0", "False", "0", "True"], res.stderr
