"""FLS on the compiled MuJoCo scene of a shipped scenario, and its benchmark entry point."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.frames import rot_from_euler
from autonomy.guidance.lawnmower import fls_swath_width_m
from scenarios.config.fls import FlsConfig
from sim.bench import fls as bench_fls
from sim.sensors.fls import FlsSensor
from sim.dynamics.truth import VehicleTruth
from sim.scene.physics import Physics


@pytest.fixture(scope="module")
def physics(cssn_scenario):
    return Physics(cssn_scenario)


def test_cssn_targets_seen_where_they_are(physics):
    """From 2 m altitude heading east, every OPI ahead is boxed at its true range and bearing."""
    world = physics.world
    cfg = FlsConfig(range_window_m=(1.0, 30.0), edge_refine_iters=4)
    mount = world.site_pos_body("fls")
    s = FlsSensor(cfg, mount, np.random.default_rng(0))
    truth = VehicleTruth(t_s=1.0, pos_ned=np.array([-4.0, 3.0, 2.0]), R_nb=rot_from_euler(0, 0, np.pi / 2),
                         rpy_rad=np.array([0, 0, np.pi / 2]), nu=np.zeros(6), nu_dot=np.zeros(6),
                         current_ned=np.zeros(3))
    out = s.measure(truth, physics.scene())
    assert out.frame.t_s == 1.0 and out.frame.fan.shape == (477, 894) and out.frame.polar.dtype == np.uint8
    assert np.allclose(out.truth.pos_ned, truth.point_ned(mount))
    geo = out.frame.geometry
    for obj, t in zip(world.objects, out.truth.objects):
        assert t.id == obj.id and t.name == obj.name
        rel = obj.centroid_ned - out.truth.pos_ned
        assert t.range_m == pytest.approx(np.linalg.norm(rel))
        assert t.visible and t.visible_fraction > 0.9, t
        x, y = geo.polar_to_pixel(t.range_m, t.azimuth_rad)
        x0, y0, x1, y1 = t.bbox_xyxy
        pad = 0.6 / geo.m_per_px  # centroid is inside its box up to the object's size
        assert x0 - pad <= x <= x1 + pad and y0 - pad <= y <= y1 + pad
        assert np.count_nonzero(out.truth.mask_fan == obj.id) > 0
    # the hull (excluded body) never shows up as a return of its own
    assert np.all(out.truth.mask_polar >= -1)


def test_swath_width_matches_guidance_formula():
    s = FlsSensor(FlsConfig(range_window_m=(1.0, 30.0), tilt_deg=12.0))
    g = s.geometry
    assert s.swath_width_m(2.0) == pytest.approx(
        fls_swath_width_m(2.0, np.deg2rad(12.0), g.fov_rad, g.vertical_beamwidth_rad, 1.0, 30.0))


def test_bench_reports_the_figures(cssn_scenario):
    res = bench_fls.run(cssn_scenario, n_frames=2)
    for key in ("frames_per_s", "rays_per_s", "raw_raycast_fraction", "n_rays", "n_beams", "n_bins"):
        assert key in res
    assert res["n_beams"] == 722 and res["n_bins"] == 1142 and 0.0 < res["raw_raycast_fraction"] < 1.0
    assert res["frames_per_s"] > 0 and res["visible_objects"] >= 3
