"""The rerun recording's paths: consecutive strips of bounded length that together are the
whole path, each re-logged only while it grows (recording and memory linear in mission time)."""

from __future__ import annotations

from sim.events.records import ObserverBase
import numpy as np
import pytest

from scenarios import load_scenario
from sim.mission import Mission
from sim.outputs.rerun_recording import RerunRecorder
from tests.support import FakeRerunStream, image_strips

pytest.importorskip("rerun")


class _Path(ObserverBase):
    def __init__(self) -> None:
        self.true: list[np.ndarray] = []
        self.est: list[np.ndarray] = []

    def on_start(self, info): pass
    def on_message(self, name, msg): pass
    def on_end(self, summary): pass

    def on_step(self, rec) -> None:
        self.true.append(np.array(rec.truth.pos_ned, dtype=float))
        self.est.append(np.array(rec.nav.pos_ned, dtype=float))


def test_paths_are_bounded_strips_that_join_into_the_whole_path(tmp_path):
    scn = load_scenario("cssn_lawnmower", ["duration_s=30", "sensors.fls.enabled=false"])
    rec = RerunRecorder(tmp_path / "fake.rrd", path_chunk_points=40, path_every_s=1.0, flush_every_s=4.0)
    rec._rec = FakeRerunStream()
    seen = _Path()
    Mission(scn, observers=[rec, seen]).run(progress=False)
    logs = rec._rec.logs
    # the batcher flushed every 4 simulated s without waiting (t = 4, 8, ..., 28), then once in full at the end
    assert rec._rec.flushes == [0.0] * 7 + [1e38]
    for name, truth in (("true", seen.true), ("estimated", seen.est)):
        keys = sorted((k for k in logs if k.startswith(f"world/path/{name}/")), key=lambda k: int(k.rsplit("/", 1)[1]))
        assert len(keys) == int(np.ceil((len(truth) - 1) / 39)) > 5  # 40 points a strip, one shared with the next
        strips = [image_strips(logs[k][-1])[0] for k in keys]  # the last version of each strip
        assert all(len(s) <= 40 for k in keys for a in logs[k] for s in image_strips(a))
        joined = np.concatenate([strips[0]] + [s[1:] for s in strips[1:]])
        np.testing.assert_allclose(joined, np.array(truth), rtol=0, atol=1e-6)  # float32 in the archetype
        # a full strip is re-logged about chunk / (path_every_s * 10 Hz) times, not once per re-log of the path
        assert max(len(logs[k]) for k in keys[:-1]) <= 40 // 10 + 2
