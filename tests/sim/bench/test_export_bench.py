"""``auvsim bench export``: each field-format writer timed alone, in CPU seconds per simulated minute."""

from __future__ import annotations

import pytest

from sim.bench.export import TimedObserver, run
from sim.events.records import ObserverBase


def test_each_writer_is_timed_and_writes_something():
    for module in ("rosbags", "pyxtf", "brping"):
        pytest.importorskip(module)
    out = run(duration_s=2.0)
    assert out["duration_s"] == 2.0
    for writer, mission in (("rosbag", "cssn_lawnmower"), ("xtf", "mcm_survey_full"), ("ping360_log", "pool_circular")):
        r = out[writer]
        assert r["mission"] == mission
        assert r["cpu_s_per_sim_min"] > 0.0 and 0.0 < r["share_of_run"] < 1.0
        assert r["run_cpu_s_per_sim_min"] > r["cpu_s_per_sim_min"] and r["bytes_per_sim_min"] > 1000


def test_the_timed_observer_forwards_hooks_and_declarations():
    class Inner(ObserverBase):
        sonar_frames = False
        sonar_truth = False

        def __init__(self):
            self.calls = []

        def on_step(self, record):
            self.calls.append(("step", record))

        def on_message(self, name, msg):
            self.calls.append((name, msg))

    inner = Inner()
    timed = TimedObserver(inner)
    assert timed.sonar_frames is False and timed.sonar_truth is False
    timed.on_step(1)
    timed.on_message("sss", 2)
    timed.on_start(None)
    timed.on_end(None)
    assert inner.calls == [("step", 1), ("sss", 2)] and timed.cpu_s >= 0.0
