"""Compiled kernels from the CLI: never imported where nothing is computed, the same bytes as the
numpy references, and one warning line when they cannot run."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

# runs the CLI in-process, then reports whether numba was imported
_RUN = """
import sys
from typer.testing import CliRunner
from lfdfuse.cli.main import app
res = CliRunner().invoke(app, sys.argv[1:])
assert res.exit_code == 0, res.output
print("numba" in sys.modules)
"""


def _python(code: str, *args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**os.environ, **(env or {})},
        timeout=600,
    )


def test_short_simulate_does_not_import_numba(tmp_path: Path) -> None:
    # a few seconds simulated: loading numba would cost more than it saves
    res = _python(_RUN, "simulate", "--world", "tee", "--duration", "5", "-o", str(tmp_path / "x.mcap"))
    assert res.stdout.strip().splitlines()[-1] == "False", res.stderr


def test_help_and_inspect_do_not_import_numba(tmp_path: Path) -> None:
    sample = ROOT / "sample_logs" / "keep-left-building.mcap"
    for args in (["--help"], ["simulate", "--help"], ["inspect", str(sample)]):
        res = _python(_RUN, *args)
        assert res.returncode == 0, res.stderr
        assert res.stdout.strip() == "False", (args, res.stdout, res.stderr)
    # and the check itself sees numba when a command computes long enough for it to pay
    res = _python(_RUN, "simulate", "--world", "tee", "--duration", "60", "-o", str(tmp_path / "x.mcap"))
    assert res.stdout.strip().splitlines()[-1] == "True", res.stderr


def _simulate(tmp: Path, name: str, env: dict[str, str], code: str = "") -> tuple[bytes, str]:
    out = tmp / f"{name}.mcap"
    script = f"{code}\nfrom lfdfuse.cli.main import app\napp()"
    # long enough that the compiled loops take over from the numpy references mid-run
    args = ["simulate", "--world", "building", "--teacher", "keep-right", "--duration", "60"]
    res = _python(script, *args, "--seed", "4", "--sensor-noise", "0.02", "-o", str(out), env=env)
    assert res.returncode == 0, res.stderr
    return out.read_bytes(), res.stderr


@pytest.fixture(scope="module")
def reference_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[bytes, str]:
    """The run with the numpy references asked for (``LFDFUSE_KERNELS=numpy``), once for the
    tests below that compare against it."""
    return _simulate(tmp_path_factory.mktemp("numpy"), "numpy", {"LFDFUSE_KERNELS": "numpy"})


def test_compiled_and_numpy_kernels_write_the_same_bytes(
    tmp_path: Path, reference_run: tuple[bytes, str]
) -> None:
    compiled, err = _simulate(tmp_path, "numba", {})
    assert "warning" not in err, err
    reference, err = reference_run
    assert "warning" not in err, err  # the references asked for: nothing to warn about
    assert compiled == reference


def test_without_numba_one_warning_line_and_the_same_bytes(
    tmp_path: Path, reference_run: tuple[bytes, str]
) -> None:
    reference, _ = reference_run
    # numba cannot be imported (as on a platform without llvmlite)
    got, err = _simulate(tmp_path, "none", {}, "import sys; sys.modules['numba'] = None")
    lines = [ln for ln in err.splitlines() if ln.startswith("warning:")]
    assert len(lines) == 1, err
    assert lines[0].startswith("warning: compiled kernels unavailable (")
    assert lines[0].endswith("; running the numpy references")
    assert got == reference
