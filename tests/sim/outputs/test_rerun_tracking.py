"""The rerun recording of a tracking mission draws each sonar-using filter's polar ROI on the
fan image of the frame it gated (paper 004 section 4), and the clusters it weighed."""

from __future__ import annotations

import cv2
from sim.events.records import ObserverBase
import numpy as np
import pytest

from autonomy.tracking.onboard import TrackingFrameResult
from scenarios import load_scenario
from sim.mission import Mission
from sim.outputs.rerun_recording import RerunRecorder
from sim.sensors.fls import FlsRender
from tests.support import FakeRerunStream, image_strips

rr = pytest.importorskip("rerun")


class _Frames(ObserverBase):
    def __init__(self) -> None:
        self.geometry = None
        self.results: list[TrackingFrameResult] = []

    def on_start(self, info): pass
    def on_step(self, rec): pass
    def on_end(self, summary): pass

    def on_message(self, name, msg):
        if isinstance(msg, FlsRender):
            self.geometry = msg.frame.geometry
        elif isinstance(msg, TrackingFrameResult):
            self.results.append(msg)


def test_recording_draws_the_roi_of_every_gated_frame_on_its_fan(tmp_path):
    scn = load_scenario("track_static_vehicle", ["duration_s=4"])
    rec = RerunRecorder(tmp_path / "fake.rrd")
    rec._rec = FakeRerunStream()
    frames = _Frames()
    mission = Mission(scn, observers=[rec, frames])
    mission.run(progress=False)
    logs = rec._rec.logs
    n = mission.summary().messages_delivered["fls"]
    assert len(frames.results) >= n - 1 >= 20  # every frame is gated (the last may wait for a pose)
    assert len(logs["sonar/fan/roi/fused"]) == len(frames.results)
    geo, s = frames.geometry, rec.fls_scale
    drawn = 0
    for res, arch in zip(frames.results, logs["sonar/fan/roi/fused"]):
        roi = res.roi["fused"]
        if roi is None:
            assert isinstance(arch, rr.Clear)
            continue
        px = image_strips(arch)[0] / s
        r, a = geo.pixel_to_polar(px[:, 0], px[:, 1])  # back to polar by the fan's own inverse
        lo, hi = max(roi.range_m - roi.half_range_m, 0.0), roi.range_m + roi.half_range_m
        assert np.allclose(np.minimum(np.abs(r - lo), np.abs(r - hi)), 0.0, atol=1e-3)
        assert np.all(np.abs(a - roi.azimuth_rad) <= roi.half_azimuth_rad + 1e-6)
        if res.chosen["fused"] is not None:  # the taken cluster's centre lies inside the drawn outline
            x0, y0, x1, y1 = res.chosen["fused"].box_xyxy_px
            poly = px.astype(np.float32).reshape(-1, 1, 2)
            assert cv2.pointPolygonTest(poly, (float(0.5 * (x0 + x1)), float(0.5 * (y0 + y1))), False) >= 0
            drawn += 1
    assert drawn >= 10
    assert len(logs["sonar/fan/clusters"]) == len(frames.results)
