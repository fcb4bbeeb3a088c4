"""The valid inputs every hostile case starts from, and a small MCAP crafting kit."""

from __future__ import annotations

import io
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import orjson
from mcap.writer import CompressionType, Writer

from lfdfuse.log.schemas import schema_text
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.sources.simulate import SimulateOptions, simulate
from lfdfuse.sources.tasks import Leg
from lfdfuse.world.model import load_world

WORLD_YAML = """\
name: box
walls:
  - [[0, 0], [12, 0], [12, 3], [0, 3], [0, 0]]
obstacles:
  - {circle: [8.0, 0.6, 0.3]}
targets:
  - {name: red, position: [11.0, 1.5], radius: 0.25}
start: [1.0, 1.5, 0.0]
"""

TASK_YAML = """\
task:
  - {target: red, style: keep-center}
"""

TABLE_YAML = """\
format: lfdfuse/fusion-table@1
behaviors: [avoid, wander_left, wander_right, wall_attract_left, wall_attract_right, sonar_avoid]
default_weights: {avoid: 0.4, wander_left: 0.3, wander_right: 0.3}
network:
  name: hand
  steps:
    - name: free
      goal: null
      fusion:
        - bac: 63
          weights: {avoid: 0.1, wander_left: 0.7, wall_attract_left: 0.2}
        - bac: 31
          weights: {avoid: 0.2, wander_left: 0.5, wall_attract_left: 0.3}
"""


@dataclass(frozen=True)
class Base:
    """Bytes of the valid inputs: ``demo.mcap``, ``seg.mcap``, ``world.yaml``, ``task.yaml``, ``table.yaml``."""

    files: dict[str, bytes]

    def __getitem__(self, name: str) -> bytes:
        return self.files[name]


def build_base(folder: Path) -> Base:
    """Simulate a short demo in the corridor and segment it (once per session)."""
    demo, seg = folder / "demo.mcap", folder / "seg.mcap"
    opts = SimulateOptions(
        world=load_world("corridor"), legs=[Leg(None, "keep-left")], teacher_name="keep-left", duration_s=6.0
    )
    simulate(opts, out=demo)
    segment_file(demo, out=seg, measure_lag=False)
    return Base(
        {
            "demo.mcap": demo.read_bytes(),
            "seg.mcap": seg.read_bytes(),
            "world.yaml": WORLD_YAML.encode(),
            "task.yaml": TASK_YAML.encode(),
            "table.yaml": TABLE_YAML.encode(),
        }
    )


# --- crafting MCAP files --------------------------------------------------------------------

Msg = tuple[str, int, bytes]  # topic, log time ns, payload


def stamp(t_ns: int) -> dict[str, int]:
    return {"sec": t_ns // 1_000_000_000, "nsec": t_ns % 1_000_000_000}


def scan(t_ns: int, ranges: list[object], *, start: object = -1.5708, end: object = 1.5708) -> bytes:
    return orjson.dumps(
        {
            "timestamp": stamp(t_ns),
            "frame_id": "base_link",
            "start_angle": start,
            "end_angle": end,
            "ranges": ranges,
            "intensities": [],
        }
    )


def cmd(t_ns: int, v: object = 0.3, w: object = 0.0) -> bytes:
    return orjson.dumps({"timestamp": stamp(t_ns), "linear": {"x": v}, "angular": {"z": w}})


def plain_log(n: int = 30, beams: int = 181, t0: int = 0, dt: int = 100_000_000) -> list[Msg]:
    """A minimal valid demo: /scan and /cmd_vel at 10 Hz."""
    out: list[Msg] = []
    for i in range(n):
        t = t0 + i * dt
        out.append(("/scan", t, scan(t, [1.0 + 0.01 * (j % 50) for j in range(beams)])))
        out.append(("/cmd_vel", t, cmd(t)))
    return out


SCHEMAS = {"/scan": "foxglove.LaserScan", "/cmd_vel": "lfdfuse.Twist", "/sonar": "foxglove.LaserScan"}


def craft(
    messages: Iterable[Msg],
    *,
    schema_encoding: str = "jsonschema",
    message_encoding: str = "json",
    schemas: dict[str, str] | None = None,
    metadata: dict[str, dict[str, str]] | None = None,
    attachments: Iterable[tuple[str, bytes]] = (),
    compression: CompressionType = CompressionType.ZSTD,
) -> bytes:
    """An MCAP file with the right framing and whatever schemas, encodings and payloads are given."""
    names = dict(SCHEMAS)
    names.update(schemas or {})
    buf = io.BytesIO()
    w = Writer(buf, compression=compression)
    w.start(profile="", library="hostile")
    channels: dict[str, int] = {}
    for topic, t, data in messages:
        if topic not in channels:
            name = names.get(topic, "lfdfuse.Twist")
            try:
                text = schema_text(name)
            except OSError:
                text = b"{}"
            sid = w.register_schema(name=name, encoding=schema_encoding, data=text)
            channels[topic] = w.register_channel(
                topic=topic, message_encoding=message_encoding, schema_id=sid
            )
        w.add_message(channel_id=channels[topic], log_time=t, publish_time=t, data=data)
    for name, meta in (metadata or {}).items():
        w.add_metadata(name, meta)
    for name, data in attachments:
        w.add_attachment(create_time=0, log_time=0, name=name, media_type="application/yaml", data=data)
    w.finish()
    return buf.getvalue()
