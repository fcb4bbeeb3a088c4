"""Every message family: encode → schema → decode round trips, and decoders that refuse what the
schema refuses (the two verdicts agree on every mutation of a valid message)."""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import jsonschema
import numpy as np
import orjson
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lfdfuse.log import lfd, lfd_tick
from lfdfuse.log import messages as msg
from lfdfuse.log.codec import MessageError
from lfdfuse.log.command import COMMAND_SOURCES, DRIVE_TOPICS, DriveCommand
from lfdfuse.log.schemas import schema
from lfdfuse.log.sensing import scan_geometry, stamp_of
from lfdfuse.robot.readings import Detection, ScanGeometry
from lfdfuse.sources.teleop.inputs import SCHEMA as TELEOP_SCHEMA
from lfdfuse.sources.teleop.inputs import Input, decode_teleop_input, teleop_input
from lfdfuse.world.model import builtin_names, load_world

T_NS = st.integers(min_value=0, max_value=2**62)
REAL = st.floats(allow_nan=False, allow_infinity=False, width=64)
UNIT = st.floats(min_value=-1.0, max_value=1.0)
ANGLE = st.floats(min_value=-math.pi, max_value=math.pi)
NAME = st.text(min_size=1, max_size=12)
NAMES = st.lists(NAME, max_size=8, unique=True).map(tuple)
OPT_NAME = st.none() | NAME
FAST = settings(max_examples=40, deadline=None)


@cache
def _validator(schema_name: str) -> jsonschema.Draft7Validator:
    return jsonschema.Draft7Validator(schema(schema_name))  # checked once by test_log


def _valid(data: dict[str, Any] | bytes, schema_name: str) -> dict[str, Any]:
    """The message as JSON after a trip through bytes, failing the test unless it meets its schema."""
    obj = orjson.loads(data) if isinstance(data, bytes) else orjson.loads(orjson.dumps(data))
    _validator(schema_name).validate(obj)
    return obj  # type: ignore[no-any-return]


# --- /lfd/* ----------------------------------------------------------------------------------


@st.composite
def behavior_rows(draw: st.DrawFn) -> lfd.BehaviorRow:
    names = draw(NAMES)
    k = len(names)
    vec = np.array(draw(st.lists(st.tuples(UNIT, UNIT), min_size=k, max_size=k)), dtype=np.float64)
    flags = st.lists(st.booleans(), min_size=k, max_size=k)
    return lfd.BehaviorRow(
        draw(T_NS), names, vec.reshape(k, 2), np.array(draw(flags), bool), np.array(draw(flags), bool)
    )


@FAST
@given(behavior_rows())
def test_behaviors_round_trip_through_their_schema(row: lfd.BehaviorRow) -> None:
    data = lfd.encode_behaviors(row.t_ns, row.names, row.vectors, row.applicable, row.goal_met)
    assert data == row.encode()
    _valid(data, lfd.BehaviorRow.SCHEMA)
    back = lfd.decode_behaviors(data)
    assert back.t_ns == row.t_ns and back.names == row.names
    assert np.array_equal(back.vectors, row.vectors) and back.vectors.shape == (len(row.names), 2)
    assert np.array_equal(back.applicable, row.applicable) and back.applicable.dtype == bool
    assert np.array_equal(back.goal_met, row.goal_met) and back.goal_met.dtype == bool
    assert back.encode() == data


MESSAGES = {
    lfd.DemoHeading: st.builds(lfd.DemoHeading, T_NS, REAL, REAL, st.booleans()),
    lfd.Bac: st.builds(lfd.Bac, T_NS, st.integers(0, 2**62), NAMES),
    lfd.SegmentMark: st.builds(lfd.SegmentMark, T_NS, st.integers(0, 2**31), OPT_NAME, OPT_NAME),
    lfd.NetworkStep: st.builds(
        lfd.NetworkStep, T_NS, OPT_NAME, OPT_NAME, st.integers(0, 2**62), st.booleans(), NAMES
    ),
    lfd.FusedVector: st.builds(
        lfd.FusedVector,
        T_NS,
        REAL,
        REAL,
        st.dictionaries(NAME, st.floats(0, 1), max_size=8).map(
            lambda w: {k: round(v, 4) for k, v in w.items()}
        ),
    ),
    lfd.NetworkEvent: st.builds(
        lfd.NetworkEvent,
        T_NS,
        st.sampled_from(lfd.NETWORK_EVENTS),
        NAME,
        st.integers(0, 2**62),
        st.sampled_from(lfd.HELP_REASONS),
    ),
    lfd.Authority: st.builds(lfd.Authority, T_NS, st.sampled_from(lfd.AUTHORITIES), st.text(max_size=20)),
    DriveCommand: st.builds(
        DriveCommand,
        T_NS,
        st.floats(-2, 2).map(lambda v: round(v, 6)),
        st.floats(-3, 3).map(lambda v: round(v, 6)),
        st.sampled_from(COMMAND_SOURCES),
        st.booleans(),
        st.none() | st.floats(0, 1e3).map(lambda v: round(v, 4)),
        st.none() | st.floats(0, 180).map(lambda v: round(v, 4)),
    ),
}


@pytest.mark.parametrize("cls", list(MESSAGES), ids=lambda c: c.TOPIC)
@FAST
@given(data=st.data())
def test_lfd_messages_round_trip_through_their_schema(cls: type[Any], data: st.DataObject) -> None:
    m = data.draw(MESSAGES[cls])
    raw = m.encode()
    _valid(raw, cls.SCHEMA)
    assert cls.decode(raw) == m
    assert cls.from_dict(orjson.loads(raw)) == m
    assert lfd.CODECS[cls.TOPIC] is cls


def test_the_module_encoders_write_what_the_classes_write() -> None:
    t = 1_700_000_000_123_456_789
    assert lfd.encode_demo(t, 0.6, -0.8, True) == lfd.DemoHeading(t, 0.6, -0.8, True).encode()
    assert lfd.decode_demo(lfd.encode_demo(t, 0.6, -0.8, True)).heading_rad == math.atan2(-0.8, 0.6)
    assert lfd.decode_bac(lfd.encode_bac(t, 5, ["a", "c"])) == lfd.Bac(t, 5, ("a", "c"))
    assert lfd.decode_segment(lfd.encode_segment(t, 2, "attract_red", "red")) == lfd.SegmentMark(
        t, 2, "attract_red", "red"
    )
    step = lfd.encode_step(t, step="go/red", goal=None, bac=3, default_weights=True, achieved=["red"])
    assert lfd.NetworkStep.decode(step) == lfd.NetworkStep(t, "go/red", None, 3, True, ("red",))
    fused = lfd.decode_fused(lfd.encode_fused(t, 0.1, 0.2, {"avoid": 0.123456, "wander": 0.876544}))
    assert fused.weights == {"avoid": 0.1235, "wander": 0.8765}  # 1e-4 on the wire
    help_ = lfd.decode_network_event(lfd.encode_help(t, step="go/red", bac=5, why="unseen BAC"))
    assert help_ == lfd.NetworkEvent(t, "help", "go/red", 5, "unseen BAC")
    assert lfd.decode_authority(lfd.encode_authority(t, "person", "keyboard")).person
    assert not lfd.decode_authority(lfd.encode_authority(t, "network")).person
    topics = {**lfd.SEGMENT_TOPICS, **lfd.EXECUTE_TOPICS, **lfd.CORRECTION_TOPICS, **DRIVE_TOPICS}
    assert set(topics) == set(lfd.CODECS) | {"/lfd/overlay"}
    assert all(lfd.CODECS[tp].SCHEMA == s for tp, s in topics.items() if tp in lfd.CODECS)


# --- the decoders refuse exactly what the schemas refuse ----------------------------------------

ODD_VALUES: list[object] = ["0.5", None, True, False, -1, 7, 2.5, [], [1], {}, {"x": 1}]


def _paths(obj: object, prefix: tuple[object, ...] = ()) -> list[tuple[object, ...]]:
    """Every field path of a JSON value (dict keys and list indices), the value itself last."""
    out: list[tuple[object, ...]] = []
    if isinstance(obj, dict):
        for k, v in obj.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            out += _paths(v, (*prefix, i))
    out.append(prefix)
    return out


def _set(obj: Any, path: tuple[object, ...], value: object) -> Any:
    if not path:
        return value
    obj = orjson.loads(orjson.dumps(obj))
    cur = obj
    for k in path[:-1]:
        cur = cur[k]
    cur[path[-1]] = value
    return obj


def _verdicts(cls: type[Any], obj: object) -> tuple[bool, bool]:
    by_schema = _validator(cls.SCHEMA).is_valid(obj)
    try:
        cls.decode(orjson.dumps(obj))
        by_decoder = True
    except MessageError:
        by_decoder = False
    return by_schema, by_decoder


SAMPLES = [
    lfd.BehaviorRow(
        7,
        ("avoid", "wander"),
        np.array([[0.5, -0.25], [1.0, 0.0]]),
        np.array([True, False]),
        np.array([False, True]),
    ),
    lfd.DemoHeading(7, 0.6, 0.8, True),
    lfd.Bac(7, 5, ("avoid", "wander")),
    lfd.SegmentMark(7, 1, "attract_red", "red"),
    lfd.NetworkStep(7, "go", None, 3, False, ("red", "green")),
    lfd.FusedVector(7, 0.5, 0.5, {"avoid": 0.25, "wander": 0.75}),
    lfd.NetworkEvent(7, "help", "reach-red", 5, "not identifiable"),
    lfd.Authority(7, "person", "foxglove client 3"),
    DriveCommand(7, 0.25, -0.5, "network", True, 1.25, 12.5),
]


@pytest.mark.parametrize("sample", SAMPLES, ids=lambda m: m.TOPIC)
def test_every_mutation_is_refused_by_the_decoder_iff_by_the_schema(sample: Any) -> None:
    cls, base = type(sample), orjson.loads(sample.encode())
    assert _verdicts(cls, base) == (True, True)
    tried = 0
    for path in _paths(base):
        for value in ODD_VALUES:
            mutated = _set(base, path, value)
            by_schema, by_decoder = _verdicts(cls, mutated)
            assert by_schema == by_decoder, (path, value, by_schema)
            tried += 1
        if path:  # a field dropped, and one added beside it
            parent, key = path[:-1], path[-1]
            holder = base
            for k in parent:
                holder = holder[k]
            if isinstance(holder, dict):
                dropped = _set(base, parent, {k: v for k, v in holder.items() if k != key})
                extra = _set(base, parent, {**holder, "extra_field": 1})
                for m in (dropped, extra):
                    by_schema, by_decoder = _verdicts(cls, m)
                    assert by_schema == by_decoder, (path, m)
    assert tried >= 4 * len(ODD_VALUES)


def test_decoders_refuse_bytes_that_are_not_a_json_object() -> None:
    for data in (b"", b"\xff", b"[1, 2]", b"3", b"[" * 3000 + b"]" * 3000, b'{"x": 1e400}'):
        for cls in lfd.CODECS.values():
            with pytest.raises(MessageError):
                cls.decode(data)


def test_from_dict_refuses_numbers_that_are_not_finite_doubles() -> None:
    good = orjson.loads(SAMPLES[0].encode())
    with pytest.raises(MessageError, match="not finite"):
        lfd.BehaviorRow.from_dict(_set(good, ("behaviors", 1, "y"), math.inf))
    with pytest.raises(MessageError, match="not finite"):
        lfd.DemoHeading.from_dict(_set(orjson.loads(SAMPLES[1].encode()), ("x",), math.nan))
    with pytest.raises(MessageError, match="too large"):
        lfd.BehaviorRow.from_dict(_set(good, ("behaviors", 0, "x"), 10**400))
    with pytest.raises(MessageError, match="too large"):
        lfd.DemoHeading.from_dict({**orjson.loads(SAMPLES[1].encode()), "y": 10**400})


def test_a_decoder_error_names_the_field() -> None:
    good = orjson.loads(SAMPLES[0].encode())
    with pytest.raises(MessageError, match="x of 'wander' is not a number"):
        lfd.BehaviorRow.decode(orjson.dumps(_set(good, ("behaviors", 1, "x"), "0.5")))
    with pytest.raises(MessageError, match="applicable of 'avoid' is not true or false"):
        lfd.BehaviorRow.decode(orjson.dumps(_set(good, ("behaviors", 0, "applicable"), 1)))
    with pytest.raises(MessageError, match="missing: 'bac'"):
        lfd.Bac.decode(b'{"timestamp": {"sec": 0, "nsec": 0}, "applicable": []}')


# --- the robot's channels (log/sensing.py) ------------------------------------------------------


@FAST
@given(
    T_NS,
    st.lists(st.floats(0, 30) | st.just(math.inf) | st.just(math.nan), min_size=1, max_size=400),
    st.floats(-math.pi, 0),
    st.floats(0.01, math.pi),
)
def test_laser_scan_round_trips_to_the_millimetre(
    t: int, ranges: list[float], start: float, span: float
) -> None:
    n = len(ranges)
    geom = ScanGeometry(start, span / max(n - 1, 1), n, 8.0)
    m = msg.laser_scan(t, np.array(ranges), geom)
    obj = orjson.loads(orjson.dumps(m))
    scan = msg.decode_scan(obj)
    assert stamp_of(obj) == t and scan.start_rad == geom.start_rad and scan.end_rad == geom.end_rad
    got, want = np.array(scan.ranges_m, dtype=np.float64), np.round(np.array(ranges), 3)
    finite = np.isfinite(want)
    assert np.array_equal(got[finite], want[finite]) and np.isnan(got[~finite]).all()
    # inf and NaN (no return) travel as JSON null, which foxglove.LaserScan does not allow: the
    # schema holds only for scans without them (the simulator's; an import's may have them)
    assert [r is None for r in obj["ranges"]] == (~finite).tolist()
    if finite.all():
        _valid(obj, "foxglove.LaserScan")
    back = scan_geometry(scan, n, 8.0)
    assert back.count == n and math.isclose(
        back.start_rad + (n - 1) * back.increment_rad, geom.end_rad, abs_tol=1e-9
    )


@FAST
@given(T_NS, REAL, REAL, ANGLE)
def test_pose_and_transform_round_trip(t: int, x: float, y: float, theta: float) -> None:
    pose = _valid(msg.pose_in_frame(t, x, y, theta), "foxglove.PoseInFrame")
    tf = _valid(msg.frame_transform(t, x, y, theta), "foxglove.FrameTransform")
    px, py, yaw = msg.decode_pose(pose)
    assert (px, py) == (x, y) and math.isclose(math.remainder(yaw - theta, 2 * math.pi), 0, abs_tol=1e-9)
    assert stamp_of(pose) == stamp_of(tf) == t
    assert tf["translation"] == pose["pose"]["position"] and tf["rotation"] == pose["pose"]["orientation"]
    assert (tf["parent_frame_id"], tf["child_frame_id"]) == (msg.MAP_FRAME, msg.ROBOT_FRAME)


@FAST
@given(T_NS, REAL, REAL)
def test_twist_round_trips(t: int, v: float, w: float) -> None:
    obj = _valid(msg.twist(t, v, w), "lfdfuse.Twist")
    assert msg.decode_twist(obj) == (v, w) and stamp_of(obj) == t


@FAST
@given(T_NS, st.lists(st.tuples(NAME, ANGLE, st.floats(0, 20)), max_size=6))
def test_target_detections_round_trip_at_their_precision(
    t: int, dets: list[tuple[str, float, float]]
) -> None:
    obj = _valid(msg.target_detections(t, [Detection(*d) for d in dets]), "lfdfuse.TargetDetections")
    back = msg.decode_detections(obj)
    assert [(d.name, d.bearing_rad, d.range_m) for d in back] == [
        (n, round(b, 6), round(r, 4)) for n, b, r in dets
    ]


# --- scenes (log/scene.py) and /teleop/input ------------------------------------------------------


@pytest.mark.parametrize("name", builtin_names())
def test_world_scenes_match_their_schema_and_draw_every_wall_and_target(name: str) -> None:
    world = load_world(name)
    obj = _valid(msg.world_scene(0, world), "foxglove.SceneUpdate")
    walls, targets = obj["entities"]
    assert len(walls["lines"]) == len(world.walls) + len(world.obstacles)
    assert [t["text"] for t in targets["texts"]] == [t.name for t in world.targets]
    assert [(c["pose"]["position"]["x"], c["pose"]["position"]["y"]) for c in targets["cylinders"]] == [
        (t.x, t.y) for t in world.targets
    ]


@FAST
@given(T_NS, st.lists(st.tuples(UNIT, UNIT), max_size=8))
def test_arrow_scenes_match_their_schema_and_point_along_their_vectors(
    t: int, vecs: list[tuple[float, float]]
) -> None:
    arrows = [msg.Arrow(vx, vy, (0.5, 0.5, 0.5)) for vx, vy in vecs]
    obj = _valid(msg.arrow_scene(t, "fusion", arrows), "foxglove.SceneUpdate")
    (ent,) = obj["entities"]
    drawn = [a for a in arrows if math.hypot(a.vx, a.vy) > 1e-6]
    assert len(ent["arrows"]) == len(drawn) and ent["frame_locked"] and stamp_of(ent) == t
    for prim, a in zip(ent["arrows"], drawn, strict=True):
        yaw = 2 * math.atan2(prim["pose"]["orientation"]["z"], prim["pose"]["orientation"]["w"])
        assert math.isclose(math.remainder(yaw - math.atan2(a.vy, a.vx), 2 * math.pi), 0, abs_tol=1e-9)


COLOR = st.tuples(*(st.floats(0.0, 1.0),) * 3)


@FAST
@given(T_NS, st.lists(st.tuples(REAL, REAL, COLOR, st.floats(0.0, 3.0)), max_size=10))
def test_the_overlay_encoder_writes_the_arrow_scenes_bytes(
    t: int, arrows: list[tuple[float, float, tuple[float, float, float], float]]
) -> None:
    """``encode_arrow_scene`` (shared position and colour objects) writes what ``arrow_scene``
    and ``arrow_scene_of`` make, byte for byte, twice in a row."""
    want = orjson.dumps(msg.arrow_scene(t, "fusion", [msg.Arrow(*a) for a in arrows]))
    assert orjson.dumps(msg.arrow_scene_of(t, "fusion", arrows)) == want
    assert msg.encode_arrow_scene(t, "fusion", arrows) == want
    assert msg.encode_arrow_scene(t, "fusion", arrows) == want


@FAST
@given(T_NS, NAMES, st.data())
def test_the_list_encoders_write_what_the_classes_write(
    t: int, names: tuple[str, ...], data: st.DataObject
) -> None:
    """The ``/lfd`` encoders the execute recorder calls each tick: the codecs' bytes."""
    k = len(names)
    vec = np.array(
        data.draw(st.lists(st.tuples(REAL, REAL), min_size=k, max_size=k)), dtype=np.float64
    ).reshape(k, 2)
    app = np.array(data.draw(st.lists(st.booleans(), min_size=k, max_size=k)), dtype=bool)
    goal = np.array(data.draw(st.lists(st.booleans(), min_size=k, max_size=k)), dtype=bool)
    row = lfd.BehaviorRow(t, names, vec, app, goal).encode()
    assert lfd.encode_behaviors(t, names, vec, app, goal) == row
    assert lfd_tick.encode_behavior_lists(t, names, vec.tolist(), app.tolist(), goal.tolist()) == row
    assert lfd_tick.BehaviorsEncoder(names).encode(t, vec.tolist(), app.tolist(), goal.tolist()) == row
    assert (
        lfd_tick.BehaviorsEncoder(names).encode_flat(t, vec.ravel().tolist(), app.tolist(), goal.tolist())
        == row
    )
    bac = data.draw(st.integers(0, 2**62))
    want = lfd.Bac(t, bac, names).encode()
    assert lfd.encode_bac(t, bac, list(names)) == want
    # spliced as the execute recorder writes them: the tick's timestamp, the rest made at another
    t0 = data.draw(T_NS)
    assert lfd_tick.stamp_head(t) + lfd_tick.tail_of(lfd_tick.bac_dict(t0, bac, names)) == want
    weights = dict(zip(names, data.draw(st.lists(REAL, min_size=k, max_size=k)), strict=True))
    x, y = data.draw(REAL), data.draw(REAL)
    assert lfd.encode_fused(t, x, y, weights) == lfd.FusedVector(t, x, y, weights).encode()
    step = data.draw(OPT_NAME)
    want = lfd.NetworkStep(t, step, None, bac, True, names).encode()
    assert (
        lfd.encode_step(t, step=step, goal=None, bac=bac, default_weights=True, achieved=list(names)) == want
    )
    assert (
        lfd_tick.stamp_head(t) + lfd_tick.tail_of(lfd_tick.step_dict(t0, step, None, bac, True, names))
        == want
    )


#: numbers at the edges of what orjson writes: zeros of both signs, the extremes, no number
EDGE = st.sampled_from([0.0, -0.0, 1e16, -1e16, 1e-5, 1e300, 5e-324, -5e-324, math.inf, -math.inf, math.nan])
ANY_REAL = st.floats(width=64) | EDGE


@FAST
@given(st.integers(0, 2**63 - 1), NAMES, st.data())
def test_the_spliced_encoders_write_the_dict_encoders_bytes_for_any_number(
    t: int, names: tuple[str, ...], data: st.DataObject
) -> None:
    """Whatever the numbers (NaN and ±inf, which a finite log never holds, as orjson writes
    them: null), the spliced encoders write the bytes of the dicts they stand for."""
    k = len(names)
    xy = [list(p) for p in data.draw(st.lists(st.tuples(ANY_REAL, ANY_REAL), min_size=k, max_size=k))]
    app = data.draw(st.lists(st.booleans(), min_size=k, max_size=k))
    goal = data.draw(st.lists(st.booleans(), min_size=k, max_size=k))
    want = orjson.dumps(lfd_tick.behaviors_dict(t, names, xy, app, goal))
    encoder = lfd_tick.BehaviorsEncoder(names)
    assert encoder.encode(t, xy, app, goal) == want
    # the same vectors as one flat list (x0, y0, x1, ...), as the execute recorder hands them
    assert encoder.encode_flat(t, [v for p in xy for v in p], app, goal) == want
    nums = data.draw(st.lists(ANY_REAL, max_size=6))
    assert lfd_tick.numbers(nums) == [orjson.dumps(v) for v in nums]
    arrows = data.draw(st.lists(st.tuples(ANY_REAL, ANY_REAL, COLOR, st.floats(0.0, 3.0) | EDGE), max_size=6))
    entity = data.draw(st.sampled_from(["fusion", "other"]))
    want = orjson.dumps(msg.arrow_scene_of(t, entity, arrows))
    assert msg.encode_arrow_scene(t, entity, arrows) == want


@FAST
@given(
    T_NS,
    st.sampled_from(["key", "message", "end", "handback"]),
    st.text(max_size=30),
    st.text(max_size=20),
    st.text(max_size=20),
    REAL,
    REAL,
    st.floats(0, 1e6),
)
def test_teleop_input_round_trips(
    t: int, kind: Any, text: str, source: str, effect: str, v: float, w: float, wall: float
) -> None:
    obj = _valid(
        teleop_input(t, Input(kind, text, source), effect=effect, command=(v, w), wall_s=wall), TELEOP_SCHEMA
    )
    back = decode_teleop_input(obj)
    assert (back.t_ns, back.kind, back.input, back.source, back.effect, back.command) == (
        t,
        kind,
        text,
        source,
        effect,
        (v, w),
    )
