from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import settings

# before any test module imports numpy: lfdfuse sets one BLAS thread per process (see its __init__)
import lfdfuse  # noqa: F401

# speed is measured in the benchmarks, never by a test: no per-example deadline (on a loaded
# machine an example of any test can take longer than hypothesis's default 200 ms)
settings.register_profile("lfdfuse", deadline=None)
settings.load_profile("lfdfuse")

ROOT = Path(__file__).resolve().parents[1]
# the shared folder beside the checkout (real data, mcap-check); LFDFUSE_SHARED overrides it
SHARED = Path(os.environ.get("LFDFUSE_SHARED", ROOT.parent / "shared"))
MCAP_CHECK = SHARED / "tools" / "mcap-check" / "run.sh"


#: the longest tests (whole closed loops, 900 s demos in generated worlds, the README's command
#: chains), started first: `make test`'s work stealing then fills the other worker with the short
#: tests beside them, instead of one long test starting last and running alone at the end
LONG_FIRST = (
    "tests/cli/test_readme.py::test_every_readme_command_works_as_written[demo-",
    "tests/cli/test_readme.py::test_every_readme_command_works_as_written",
    "tests/support/test_generated.py::",
    "tests/parallel/test_dask.py::test_evaluate_many_logs_serial_and_on_two_workers_are_byte_identical",
    "tests/execute/test_keyboard.py::",
    "tests/execute/test_correction_fixes.py::",
    "tests/execute/test_repair.py::test_a_table_that_leaves_the_teacher",
    "tests/execute/test_repair.py::test_a_goal_step_whose_sub_goals_mislead",
    "tests/execute/test_off_route.py::test_the_turn_out_of_a_spur",
    "tests/execute/test_off_route.py::test_a_spur_just_past_a_corner",
    "tests/estimate/test_approach.py::test_a_goal_driven_past",
    "tests/cli/test_cli.py::test_the_installed_command_runs_the_whole_pipeline",
    "tests/behaviors/test_reference_tables.py::test_tables_are_byte_identical_to_the_reference",
    "tests/execute/test_closed_loop.py::test_three_goal_task_from_perturbed_starts",
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Run :data:`LONG_FIRST` first, in its order; every other test keeps its place."""

    def rank(item: pytest.Item) -> int:
        return next((i for i, p in enumerate(LONG_FIRST) if item.nodeid.startswith(p)), len(LONG_FIRST))

    items.sort(key=rank)


def mcap_check(path: Path) -> str:
    """Run the independent TypeScript MCAP reader/validator; returns its output, fails on problems."""
    if not MCAP_CHECK.exists() or shutil.which("node") is None:
        pytest.skip("mcap-check (../shared/tools) or node is not available")
    res = subprocess.run(["bash", str(MCAP_CHECK), str(path)], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stdout + res.stderr
    return res.stdout


@pytest.fixture(scope="session")
def dask_cluster() -> Iterator[Any]:
    """One 2-worker Dask LocalCluster (processes, one thread each) for every test that needs one."""
    pytest.importorskip("distributed")
    from lfdfuse.parallel import open_executor

    with open_executor(workers=2) as ex:
        yield ex


@pytest.fixture(scope="session")
def sample_dir() -> Path:
    return ROOT / "sample_logs"


@pytest.fixture(scope="session")
def three_goal_segmented(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``sample_logs/three-goals-building.mcap`` segmented as ``lfdfuse segment`` does by default,
    once per session: tests read it and write nothing beside it."""
    from lfdfuse.segment.pipeline import segment_file

    out = tmp_path_factory.mktemp("three-goals") / "three.seg.mcap"
    segment_file(ROOT / "sample_logs" / "three-goals-building.mcap", out=out)
    return out


@pytest.fixture(scope="session")
def keep_left_segmented(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``sample_logs/keep-left-building.mcap`` segmented as ``lfdfuse segment`` does by default,
    once per session: tests read it and write nothing beside it."""
    from lfdfuse.segment.pipeline import segment_file

    out = tmp_path_factory.mktemp("keep-left") / "keep-left.seg.mcap"
    segment_file(ROOT / "sample_logs" / "keep-left-building.mcap", out=out)
    return out


@pytest.fixture(scope="session")
def three_goal_table(three_goal_segmented: Path) -> Any:
    """The table the default estimate learns from :func:`three_goal_segmented` (a frozen
    ``FusionTable``), learned once per session for every test that drives or reads it."""
    from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
    from lfdfuse.segment.read import read_segmented

    table, _, _ = estimate_run(read_segmented(three_goal_segmented), opts=EstimateOptions())
    return table
