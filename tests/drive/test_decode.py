"""Decoding both dialects into our records: round trips through rosbags CDR and our own JSON."""

from __future__ import annotations

import math

import numpy as np
import orjson
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_typestore

from lfdfuse.drive.decode import (
    DecodeError,
    LiveOdom,
    LiveScan,
    LiveTf,
    LiveTwist,
    Role,
    twist_encoder,
)
from lfdfuse.drive.decoders import REGISTRY, decoder_for, json_message, register, role_of
from lfdfuse.drive.foxglove.wire import ServerChannel
from lfdfuse.log import messages as msg
from lfdfuse.sim.sensors import LaserParams
from tests.support.bridge_sim import _tf, cdr_odom, cdr_scan, cdr_tf

STORE = get_typestore(Stores.ROS2_HUMBLE)


def channel(name: str, encoding: str = "cdr", *, with_schema: bool = True) -> ServerChannel:
    text = STORE.generate_msgdef(name)[0] if encoding == "cdr" and with_schema else ""
    return ServerChannel(1, "/t", encoding, name, "ros2msg" if encoding == "cdr" else "jsonschema", text)


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.one_of(st.floats(0.0, 20.0), st.just(math.inf), st.just(math.nan)), min_size=1, max_size=50),
    st.floats(-math.pi, math.pi),
    st.booleans(),
)
def test_cdr_scan_round_trip_and_no_return(ranges: list[float], start: float, with_schema: bool) -> None:
    data = cdr_scan(1_700_000_000_123_456_789, np.array(ranges), start, 0.01, 12.0, "rplidar_link")
    rec = decoder_for(channel("sensor_msgs/msg/LaserScan", with_schema=with_schema))(data)
    assert isinstance(rec, LiveScan) and rec.frame == "rplidar_link"
    r = rec.record
    assert r.t_ns == 1_700_000_000_123_456_789 and r.count == len(ranges) and r.max_range_m == 12.0
    assert abs(r.start_rad - start) < 1e-6
    want = np.asarray(ranges, dtype=np.float32).astype(np.float64)
    bad = ~np.isfinite(want) | (want < 0.05) | (want >= 12.0)  # the rig's range_min is 0.05 m
    assert np.all(np.isinf(r.ranges_m[bad])) and np.array_equal(r.ranges_m[~bad], want[~bad])


@settings(max_examples=30, deadline=None)
@given(st.floats(-50, 50), st.floats(-50, 50), st.floats(-math.pi + 1e-6, math.pi - 1e-6))
def test_cdr_odometry_and_tf(x: float, y: float, th: float) -> None:
    odom = decoder_for(channel("nav_msgs/msg/Odometry"))(cdr_odom(5, x, y, th))
    assert isinstance(odom, LiveOdom) and odom.base_frame == "base_link"
    assert (odom.x, odom.y) == pytest.approx((x, y)) and odom.theta == pytest.approx(th, abs=1e-9)
    tf = decoder_for(channel("tf2_msgs/msg/TFMessage"))(cdr_tf([_tf(5, "base_link", "laser", x, y, th)]))
    assert isinstance(tf, LiveTf) and tf.transforms[0].parent == "base_link"
    m = np.array(tf.transforms[0].matrix)
    assert m[0, 3] == pytest.approx(x) and math.atan2(m[1, 0], m[0, 0]) == pytest.approx(th, abs=1e-9)


@settings(max_examples=30, deadline=None)
@given(st.floats(-2, 2), st.floats(-3, 3))
def test_twist_encoders_round_trip(v: float, w: float) -> None:
    cdr = twist_encoder(("cdr", "json"))
    assert cdr.encoding == "cdr" and "geometry_msgs/Vector3 linear" in cdr.schema
    back = decoder_for(channel("geometry_msgs/msg/Twist"))(cdr.encode(v, w, 0))
    assert back == LiveTwist(v, w)
    js = twist_encoder(("json",))
    assert js.encoding == "json"
    assert decoder_for(channel("geometry_msgs/msg/Twist", "json"))(js.encode(v, w, 0)) == LiveTwist(v, w)
    for enc in (twist_encoder(("cdr",), stamped=True), twist_encoder(("json",), stamped=True)):
        name = "geometry_msgs/msg/TwistStamped"
        assert enc.schema_name == name
        assert decoder_for(channel(name, enc.encoding))(enc.encode(v, w, 1_700_000_000_5)) == LiveTwist(v, w)


def test_a_twist_stamped_carries_the_robot_clock() -> None:
    enc = twist_encoder(("cdr",), stamped=True)
    m = STORE.deserialize_cdr(
        enc.encode(0.2, -0.1, 1_700_000_001_250_000_000), "geometry_msgs/msg/TwistStamped"
    )
    assert (m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id) == (
        1_700_000_001,
        250_000_000,
        "base_link",
    )


def test_twist_encoder_needs_cdr_or_json() -> None:
    with pytest.raises(DecodeError, match="neither CDR nor JSON"):
        twist_encoder(("protobuf",))


def test_lfdfuse_json_dialect() -> None:
    geom = LaserParams().geometry
    ranges = np.linspace(0.5, 8.0, geom.count)
    rec = decoder_for(channel("foxglove.LaserScan", "json"))(orjson.dumps(msg.laser_scan(7, ranges, geom)))
    assert isinstance(rec, LiveScan) and rec.frame == "base_link"
    assert rec.record.count == geom.count and rec.record.increment_rad == pytest.approx(geom.increment_rad)
    assert np.isinf(rec.record.ranges_m[-1]) and np.allclose(
        rec.record.ranges_m[:-1], np.round(ranges[:-1], 3)
    )
    pose = decoder_for(channel("foxglove.PoseInFrame", "json"))(
        orjson.dumps(msg.pose_in_frame(7, 1.0, 2.0, 0.5))
    )
    assert isinstance(pose, LiveOdom) and (pose.x, pose.y) == (1.0, 2.0) and pose.theta == pytest.approx(0.5)
    assert role_of(channel("lfdfuse.TargetDetections", "json")) is Role.TARGETS
    assert role_of(channel("foxglove.SceneUpdate", "json")) is None


@pytest.mark.parametrize(
    ("name", "encoding", "payload"),
    [
        ("sensor_msgs/msg/LaserScan", "cdr", b"\x00\x01\x00\x00garbage"),
        ("sensor_msgs/msg/LaserScan", "cdr", b""),
        ("nav_msgs/msg/Odometry", "cdr", b"\x00\x01"),
        ("foxglove.LaserScan", "json", b"{not json"),
        ("foxglove.LaserScan", "json", b'{"timestamp": {"sec": 0, "nsec": 0}}'),
        ("foxglove.PoseInFrame", "json", b"[]"),
        ("geometry_msgs/msg/Twist", "json", b'{"linear": {"x": "fast"}}'),
    ],
)
def test_malformed_payloads_raise_decode_error(name: str, encoding: str, payload: bytes) -> None:
    with pytest.raises(DecodeError):
        decoder_for(channel(name, encoding))(payload)


def test_a_bad_schema_is_a_decode_error() -> None:
    with pytest.raises(DecodeError, match="ros2msg schema"):
        decoder_for(ServerChannel(1, "/scan", "cdr", "sensor_msgs/msg/LaserScan", "ros2msg", "flot32 ]["))


def test_the_registry_holds_both_families_and_takes_a_new_type() -> None:
    cdr_pairs = {k for k in REGISTRY if k[0] == "cdr"}
    assert {name for _, name in cdr_pairs} == {
        "sensor_msgs/msg/LaserScan",
        "nav_msgs/msg/Odometry",
        "tf2_msgs/msg/TFMessage",
        "geometry_msgs/msg/Twist",
        "geometry_msgs/msg/TwistStamped",
    }
    json_roles = {name: e.role for (enc, name), e in REGISTRY.items() if enc == "json"}
    assert json_roles["foxglove.LaserScan"] is Role.SCAN and json_roles["lfdfuse.Twist"] is Role.CMD
    assert len(json_roles) == 8
    # a new message type is one register call: role_of and decoder_for know it at once
    ch = ServerChannel(1, "/flat", "json", "test.FlatTwist", "jsonschema", "")
    assert role_of(ch) is None
    try:
        register("json", "test.FlatTwist", Role.CMD, json_message(lambda m: LiveTwist(m["v"], m["w"])))
        assert role_of(ch) is Role.CMD
        assert decoder_for(ch)(b'{"v": 0.5, "w": -0.25}') == LiveTwist(0.5, -0.25)
        with pytest.raises(DecodeError, match="undecodable test.FlatTwist"):
            decoder_for(ch)(b'{"v": 0.5}')
    finally:
        del REGISTRY[("json", "test.FlatTwist")]
