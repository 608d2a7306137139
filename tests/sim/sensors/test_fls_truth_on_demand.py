"""An FLS frame rendered without its objects' ground truth (``truth=False``) is the full
render's frame byte for byte, draws the same noise, keeps the pose, and refuses to give what it
did not compute."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from sim.sensors.fls import FlsSensor
from sim.sensors.sonar.ground_truth import SonarGroundTruth, SonarTruthNotComputedError


@pytest.fixture
def paired(monkeypatch):
    """Every render of the test is made twice from the same noise state, without and with the
    truth; the bytes that must agree are compared here, the full render is returned."""
    inner = FlsSensor.render
    seen = {"frames": 0, "objects": 0, "k_speckle": 0}

    def both(self, *args, **kwargs):
        state = copy.deepcopy(self.rng.bit_generator.state)
        lean = inner(self, *args, **kwargs, truth=False)
        state_after_lean = copy.deepcopy(self.rng.bit_generator.state)
        self.rng.bit_generator.state = state
        full = inner(self, *args, **kwargs, truth=True)
        assert repr(self.rng.bit_generator.state) == repr(state_after_lean)  # same draws
        for a, b in ((lean.frame.polar, full.frame.polar), (lean.frame.fan, full.frame.fan),
                     (lean.mean_intensity, full.mean_intensity), (lean.intensity, full.intensity),
                     (lean.truth.pos_ned, full.truth.pos_ned), (lean.truth.R_ns, full.truth.R_ns)):
            assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
        assert lean.frame.t_s == full.frame.t_s == lean.truth.t_s == full.truth.t_s
        assert full.truth.objects_computed and not lean.truth.objects_computed
        seen["frames"] += 1
        seen["objects"] += sum(o.visible for o in full.truth.objects)
        seen["k_speckle"] += self.echo.speckle == "k"
        return full

    monkeypatch.setattr(FlsSensor, "render", both)
    return seen


def test_bench_frames_without_truth_are_the_full_renders_bytes(paired):
    from scenarios.load import load_scenario
    from sim.bench import fls as bench_fls

    bench_fls.run(load_scenario("cssn_lawnmower"), 2, without_truth=False, baseline=False)
    assert paired["frames"] == 3 and paired["objects"] > 0  # warm-up + 2 frames, with targets in view


def test_k_clutter_frames_without_truth_are_the_full_renders_bytes(paired):
    from sim.dataset.generate import RANDOMIZATION_PRESETS, RenderSettings, fls_config, scene_spec
    from sim.dataset.scene_render import render_frames
    from sim.rng import component_rng

    spec = scene_spec(0, 1, RANDOMIZATION_PRESETS["train"])
    render_frames(spec, fls_config(spec, RenderSettings()), component_rng(0, "dataset/fls/1"), 2)
    assert paired["frames"] == 2 and paired["k_speckle"] == 2  # the K texture reads the clutter mask


def test_reading_the_truth_a_frame_was_rendered_without_raises():
    from scenarios.load import load_scenario
    from sim.scene.world import build_world
    from sim.sensors.raycast import MujocoRayCaster

    scn = load_scenario("cssn_lawnmower")
    world = build_world(scn)
    caster = MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                             world.vehicle_body_id)
    sensor = FlsSensor(scn.sensors.fls, rng=np.random.default_rng(0))
    sensor.render_truth = False
    target = world.objects[0].centroid_ned
    pos = np.array([target[0] - 8.0, target[1], target[2] - 3.0])
    lean = sensor.render(1.5, pos, np.eye(3), caster, world.objects)  # the sensor's default
    assert not lean.truth.objects_computed
    assert lean.truth.t_s == 1.5 and np.array_equal(lean.truth.pos_ned, pos)
    for read in (lambda t: t.objects, lambda t: t.mask_polar, lambda t: t.mask_fan,
                 lambda t: t.object(world.objects[0].id)):
        with pytest.raises(SonarTruthNotComputedError, match="without its objects' ground truth"):
            read(lean.truth)
    full = sensor.render(1.5, pos, np.eye(3), caster, world.objects, truth=True)
    assert full.truth.objects_computed and full.truth.object(world.objects[0].id).in_fov
    with pytest.raises(ValueError, match="both given or both None"):
        SonarGroundTruth(0.0, full.truth.mask_polar, None, pos, np.eye(3))
