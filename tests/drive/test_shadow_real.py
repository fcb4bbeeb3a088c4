"""A real robot's bag replayed as ``foxglove_bridge`` would stream it, with ``drive --shadow``.

The TurtleBot 4 log of ``../shared/realdata`` (a person at a keyboard): imported, segmented
(at lag 0, as the live comparison pairs each scan with the command held when it arrives) and
estimated; its MCAP then replays through a Foxglove server with the bag's own ``ros2msg``
schemas and CDR payloads. The live agreement must be the table's heading error on the same
log computed offline, step for step, and sit where ``evaluate``'s held-out fit puts the fused
heading (read as a heading, as the live agreement is, not as a key press); the
shadow log itself segments like the imported bag, step for step.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np
import pytest

from lfdfuse.estimate.pipeline import EstimateOptions, estimate_run
from lfdfuse.evaluate.holdout import evaluate, predict, slice_run
from lfdfuse.evaluate.roundtrip import heading_errors
from lfdfuse.log.reader import iter_messages
from lfdfuse.segment.pipeline import segment_file
from lfdfuse.segment.read import read_segmented
from lfdfuse.sources.importers.convert import import_log
from tests.conftest import SHARED, mcap_check
from tests.drive.conftest import in_thread, start_drive
from tests.support.bridge_sim import BagReplay

BAG = SHARED / "realdata" / "ros2" / "macfirst_floor_take_2.mcap"


@pytest.mark.skipif(not BAG.exists(), reason="../shared/realdata is not available")
def test_shadow_agreement_on_a_real_bag_matches_evaluate(tmp_path: Path) -> None:
    demo, seg = tmp_path / "tb.mcap", tmp_path / "tb.seg.mcap"
    import_log(BAG, out=demo)
    segment_file(demo, out=seg, lag_s=0.0, measure_lag=False)
    run = read_segmented(seg)
    table, _, _ = estimate_run(run, opts=EstimateOptions(seed=0), name="tb")
    offline = np.degrees(np.abs(heading_errors(table, run)))
    ev = evaluate(run)

    out = tmp_path / "shadow.mcap"
    with BagReplay(BAG, speed=6.0) as bag:
        live = start_drive(table, bag.url, out=out, shadow=True)

        def replay() -> None:
            assert bag.wait_for_subscriber()
            bag.run()
            time.sleep(0.3)
            live.stopper.stop("replayed")

        th = in_thread(replay)
        s = live.join(90)
        th.join(5)
    assert s.sent == 0 and bag.listener.channels == {}  # shadow: nothing advertised, nothing sent
    assert s.mount_from == "tf (base_link → rplidar_link)"  # yaw +90°, from /tf_static
    assert s.ticks == 357  # every scan of the bag
    assert s.agreement_ticks == len(offline) == int(run.informative.sum())
    assert s.agreement_deg == pytest.approx(float(offline.mean()), abs=1e-3)
    # evaluate reads a keyboard log's predictions as key presses; the live agreement is the raw
    # fused heading's error, so it is compared with evaluate's fit read the same way
    n = len(run.t_ns)
    cut = int(math.floor(n * (1.0 - ev.holdout)))
    train, test = slice_run(run, 0, cut), slice_run(run, cut, n)
    steps = np.nonzero(test.informative)[0]
    fit, _, _ = estimate_run(train, opts=EstimateOptions(seed=0), name="fused")
    demo = np.arctan2(test.demo[steps, 1], test.demo[steps, 0])
    miss = predict(fit, test, steps) - demo
    fused = float(np.degrees(np.abs(np.arctan2(np.sin(miss), np.cos(miss)))).mean())
    assert abs(s.agreement_deg - fused) < 5.0, (s.agreement_deg, fused)
    assert s.agreement_deg < ev.methods["arbitration"].heading_error_deg
    assert any(n.startswith("agreement so far:") for n in live.notes)
    # the log holds the robot's own commands on /cmd_vel and the network's beside them
    report = json.loads(mcap_check(out))
    assert report["ok"] and report["counts"]["/lfd/command"] == 357
    cmds = [json.loads(d) for _, _, _, d in iter_messages(out, topics=["/lfd/command"])]
    assert not any(c["sent"] for c in cmds)
    errs = [c["heading_error_deg"] for c in cmds if c["heading_error_deg"] is not None]
    assert np.mean(errs) == pytest.approx(s.agreement_deg, abs=1e-3)
    # and the shadow log is itself a demonstration: it segments like the import, step for step
    segment_file(out, out=tmp_path / "shadow.seg.mcap", lag_s=0.0, measure_lag=False)
    again = read_segmented(tmp_path / "shadow.seg.mcap")
    assert len(again.t_ns) == len(run.t_ns) and int(again.informative.sum()) == int(run.informative.sum())
    assert np.array_equal(again.bac, run.bac)
    assert np.allclose(again.demo[again.informative], run.demo[run.informative], atol=1e-6)
