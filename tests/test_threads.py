"""lfdfuse runs numpy's BLAS on one thread per process unless the user says otherwise.

The estimator's products are small (steps × a few behaviours × particles), where OpenBLAS's
threads cost more than they give; the cores go to ``--workers`` and the test runner instead.
"""

from __future__ import annotations

import os
import subprocess
import sys

PROBE = "import lfdfuse, os; print(os.environ['OPENBLAS_NUM_THREADS'], os.environ['OMP_NUM_THREADS'])"


def _probe(**env: str) -> str:
    base = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    out = subprocess.run(
        [sys.executable, "-c", PROBE], env=base | env, capture_output=True, text=True, check=True
    )
    return out.stdout.strip()


def test_importing_lfdfuse_asks_for_one_blas_thread() -> None:
    assert _probe() == "1 1"


def test_a_users_thread_setting_is_kept() -> None:
    assert _probe(OPENBLAS_NUM_THREADS="4", OMP_NUM_THREADS="3") == "4 3"
