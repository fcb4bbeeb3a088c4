"""MCAP logs: round trips, schemas, determinism, and an independent reader."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import orjson
import pytest

from lfdfuse.log import read_run
from lfdfuse.log.reader import file_info, iter_messages
from lfdfuse.log.schemas import schema
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world
from tests.conftest import ROOT, SHARED, mcap_check


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, object]:
    out = tmp_path_factory.mktemp("log") / "demo.mcap"
    opts = SimulateOptions(
        world=load_world("building"),
        legs=[Leg("red", "keep-left")],
        teacher_name="t",
        duration_s=30,
        seed=4,
        sensor_noise_m=0.01,
    )
    return out, simulate(opts, out=out)


def test_written_run_reads_back_as_the_same_arrays(demo: tuple[Path, object]) -> None:
    path, summary = demo
    run = read_run(path)
    assert len(run) == summary.steps  # type: ignore[attr-defined]
    assert run.ranges_m.shape == (summary.steps, 181)  # type: ignore[attr-defined]
    assert np.allclose(run.pose, summary.poses, atol=1e-12)  # type: ignore[attr-defined]
    assert (np.diff(run.t_ns) == 100_000_000).all()
    assert run.geometry.count == 181 and run.geometry.start_rad == pytest.approx(-np.pi / 2)
    assert run.geometry.max_range_m == 8.0
    assert np.allclose(run.ranges_m[:, 90 + 90], summary.left_m, atol=5e-4)  # type: ignore[attr-defined]
    assert run.world_yaml is not None and "building" in run.world_yaml
    assert run.metadata["seed"] == "4" and run.metadata["world"] == "building"
    assert len(run.cmd_t_ns) == summary.steps  # type: ignore[attr-defined]


def test_every_message_matches_its_schema(demo: tuple[Path, object]) -> None:
    path, _ = demo
    seen = set()
    for topic, schema_name, _t, data in iter_messages(path):
        if topic in seen and topic != "/targets":
            continue
        seen.add(topic)
        jsonschema.validate(orjson.loads(data), schema(schema_name))
    assert seen == {"/scan", "/sonar", "/pose", "/tf", "/cmd_vel", "/targets", "/world"}


def test_our_schemas_are_valid_json_schemas() -> None:
    for p in (ROOT / "schemas").rglob("*.json"):
        jsonschema.Draft7Validator.check_schema(json.loads(p.read_text()))


def test_same_seed_gives_byte_identical_files(tmp_path: Path) -> None:
    world = load_world("corridor")
    files = []
    for name, seed in (("a", 9), ("b", 9), ("c", 10)):
        opts = SimulateOptions(
            world=world,
            legs=[Leg(None, "slalom")],
            teacher_name="slalom",
            duration_s=20,
            seed=seed,
            sensor_noise_m=0.02,
        )
        simulate(opts, out=tmp_path / f"{name}.mcap")
        files.append((tmp_path / f"{name}.mcap").read_bytes())
    assert files[0] == files[1]
    assert files[0] != files[2]


def test_file_info_reads_a_real_ros2_bag() -> None:
    bag = SHARED / "realdata" / "ros2" / "macfirst_floor_take_2.mcap"
    if not bag.exists():
        pytest.skip("shared real data not present")
    info = file_info(bag)
    assert info.channels["/scan"][0] == "sensor_msgs/msg/LaserScan" and info.channels["/scan"][2] == 357
    assert info.channels["/cmd_vel"][2] == 192


def test_independent_reader_accepts_our_files(demo: tuple[Path, object]) -> None:
    path, _ = demo
    report = json.loads(mcap_check(path))
    assert report["ok"] and report["outOfOrder"] == 0
    assert report["metadata"] == ["lfdfuse"] and report["attachments"] == ["world.yaml"]
    assert report["schemas"]["/scan"] == "foxglove.LaserScan"


def _numbers_close(a: object, b: object) -> bool:
    """The same JSON structure, every number within 1e-9 of the other's."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_numbers_close(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_numbers_close(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float):
        return a == b or abs(a - b) <= 1e-9
    return type(a) is type(b) and a == b


def _messages(path: Path) -> list[tuple[str, int, bytes]]:
    from mcap.reader import make_reader

    with path.open("rb") as f:
        return [(ch.topic, m.log_time, m.data) for _, ch, m in make_reader(f).iter_messages()]


def _records(path: Path) -> tuple[list[tuple[str, dict[str, str]]], list[tuple[str, bytes]]]:
    from mcap.reader import make_reader

    with path.open("rb") as f:
        r = make_reader(f)
        return [(m.name, dict(m.metadata)) for m in r.iter_metadata()], [
            (a.name, bytes(a.data)) for a in r.iter_attachments()
        ]


def test_sample_logs_are_what_the_code_generates(tmp_path: Path) -> None:
    """The shipped sample logs are what ``make sample-logs`` writes: the same messages on the same
    channels at the same times, every number within 1e-9 of the shipped one. Not byte for byte:
    a release of an unpinned dependency may change the last bit of a result (a fresh install on
    2026-12-03 changed 158 of 21,963 messages by at most 3.3e-16, with numpy 2.4.6 or 2.4.5 alike,
    and the runs did not drift apart); byte-identical output from the same
    environment is :func:`test_same_seed_gives_byte_identical_files`'s. Metadata and attachments
    match exactly."""
    from tests.support.samples import generate

    for made in generate(tmp_path):
        shipped = ROOT / "sample_logs" / made.name
        ours, theirs = _messages(made), _messages(shipped)
        assert [m[:2] for m in ours] == [m[:2] for m in theirs], f"run `make sample-logs` ({made.name})"
        for (topic, t, a), (_, _, b) in zip(ours, theirs, strict=True):
            assert a == b or _numbers_close(orjson.loads(a), orjson.loads(b)), (
                f"run `make sample-logs` ({made.name}: {topic} at {t} ns)"
            )
        assert _records(made) == _records(shipped), f"run `make sample-logs` ({made.name})"
        assert shipped.stat().st_size < 2_000_000
    assert (ROOT / "sample_logs" / "three-goals.task.yaml").read_text() == (
        tmp_path / "three-goals.task.yaml"
    ).read_text()
