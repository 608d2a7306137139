"""Moving targets: seeded kinematics (paper 004 eq. 6), bubble plumes, and the FLS echo of a
diver at its true range and azimuth at ping time."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scenarios.config.movers import BubbleConfig, MoverConfig
from scenarios.schema import Scenario
from sim.scene.physics import Physics
from sim.sensors.fls import FlsSensor
from sim.sensors.registry import build_sensors
from sim.scene.target_motion import BubblePlumes, ManoeuvreTrajectory


def test_trajectory_integrates_its_own_kinematics():
    """Exact arcs agree with a fine Euler integration of n' = u cos c, e' = u sin c, d' = w, c' = r."""
    cfg = MoverConfig(name="d", initial_pos_ned=(0.0, 0.0, 5.0), course_rate_sigma_dps=10.0, heave_sigma_mps=0.05,
                      manoeuvre_mean_s=5.0)
    traj = ManoeuvreTrajectory(cfg, np.random.default_rng(1), 60.0)
    dt = 1e-3
    t = np.arange(0.0, 60.0, dt)
    _, course, rate, surge, heave = traj.state_at(t)
    vel = np.stack([surge * np.cos(course), surge * np.sin(course), heave], axis=1)
    euler = np.array([0.0, 0.0, 5.0]) + np.cumsum(vel * dt, axis=0)
    pos_exact, *_ = traj.state_at(t + dt)
    assert np.max(np.abs(euler - pos_exact)) < 0.02
    assert len(traj.t0_s) > 5 and np.std(traj.course_rate_radps) > 0.05  # it manoeuvres
    lo, hi = cfg.depth_band_m
    assert np.all((pos_exact[:, 2] >= lo - 1e-9) & (pos_exact[:, 2] <= hi + 1e-9))
    again = ManoeuvreTrajectory(cfg, np.random.default_rng(1), 60.0)
    np.testing.assert_array_equal(again.state_at(t[::1000])[0], traj.state_at(t[::1000])[0])


def test_bubbles_rise_at_their_speed_and_are_recycled():
    cfg = MoverConfig(name="d", initial_pos_ned=(0.0, 0.0, 8.0), surge_sigma_mps=0.0, course_rate_sigma_dps=0.0,
                      heave_sigma_mps=0.0)
    traj = ManoeuvreTrajectory(cfg, np.random.default_rng(0), 100.0)
    bcfg = BubbleConfig(rise_speed_sigma_mps=0.0, dispersion_mps=0.0)
    plume = BubblePlumes(bcfg, traj, np.random.default_rng(2), 100.0)
    t1 = plume.release_t_s[3] + 2.0
    p1, alive1 = plume.positions_at(t1)
    p2, alive2 = plume.positions_at(t1 + 1.0)
    both = alive1 & alive2
    assert both.sum() >= bcfg.per_breath
    np.testing.assert_allclose(p2[both, 2] - p1[both, 2], -bcfg.rise_speed_mps, atol=1e-12)
    # at most lifetime / period clusters in the water
    assert alive1.sum() <= plume.n_bubbles


def _crossing_scenario(**fls) -> Scenario:
    diver = dict(name="diver", kind="diver", initial_pos_ned=(6.0, -0.5, 5.0), initial_course_deg=90.0,
                 surge_mps=0.5, surge_sigma_mps=0.0, course_rate_sigma_dps=0.0, heave_sigma_mps=0.0,
                 reflectivity=0.9)
    return Scenario(
        name="crossing", duration_s=10.0,
        world={"seabed": {"depth_m": 30.0}, "movers": [diver]},
        vehicle={"model": "bluerov2_heavy", "initial_pos_ned": (0.0, 0.0, 5.0)},
        sensors={"fls": {"preset": "aris3000_lf", "tilt_deg": 0.0, "rate_hz": 6.0, "mount_pos_body_m": (0.3, 0.0, 0.0),
                         **fls}},
    )


def test_fls_echo_of_a_moving_diver_is_where_the_diver_is_at_ping_time():
    scn = _crossing_scenario()
    phys = Physics(scn)
    phys.reset(scn.vehicle.initial_pos_ned, (0.0, 0.0, 0.0))
    fls: FlsSensor = build_sensors({"fls": scn.sensors.fls}, phys.site_pos_body, 0)["fls"]
    n = int(round(2.0 / phys.dt_s))
    phys.advance(np.zeros(phys.params.n_thrusters), n)
    truth = phys.truth()
    render = fls.measure(truth, phys.scene(), noise=False)
    # independent expectation: the diver moves east at 0.5 m/s from (6, -0.5, 5)
    t = phys.t_s
    diver_ned = np.array([6.0, -0.5 + 0.5 * t, 5.0])
    head = truth.point_ned(fls.mount_pos_body_m)
    rel = (truth.R_nb @ fls.R_bs).T @ (diver_ned - head)
    exp_range, exp_az = float(np.linalg.norm(rel)), float(math.atan2(rel[1], rel[0]))
    (obj,) = [o for o in render.truth.objects if o.name == "diver"]
    assert obj.visible and obj.in_fov
    assert obj.range_m == pytest.approx(exp_range, abs=1e-6) and obj.azimuth_rad == pytest.approx(exp_az, abs=1e-6)
    # the labelled echo: nearest bin at the capsule's near surface, beams around the azimuth
    g = fls.geometry
    beams, bins = np.nonzero(render.truth.mask_polar == obj.id)
    assert beams.size > 0
    seg_e = np.clip(head[1], diver_ned[1] - 0.7, diver_ned[1] + 0.7)  # closest point on the capsule axis
    near_m = math.hypot(diver_ned[0] - head[0], seg_e - head[1]) - 0.2
    first_m = g.window_near_m + bins.min() * g.range_resolution_m
    assert abs(first_m - near_m) < 3 * g.range_resolution_m
    az = g.beam_azimuths_rad()[beams]
    assert az.min() - g.beam_spacing_rad <= exp_az <= az.max() + g.beam_spacing_rad
    assert abs(0.5 * (az.min() + az.max()) - exp_az) < math.radians(2.0)
    # ... and not where it started (1 m west at t = 0)
    rel0 = (truth.R_nb @ fls.R_bs).T @ (np.array([6.0, -0.5, 5.0]) - head)
    assert abs(math.atan2(rel0[1], rel0[0]) - 0.5 * (az.min() + az.max())) > math.radians(3.0)
    # the echo is strong there: the object bins outshine the water around them
    mean = render.mean_intensity
    assert np.median(mean[beams, bins]) > 10 * np.median(mean)


@pytest.mark.parametrize("depth_m", [4.6, 5.0, 5.4])
def test_fls_echo_of_a_diver_along_the_beam_stays_on_the_diver(depth_m):
    """A diver lying along the beam (course straight away from the sonar), 12 m ahead, level
    with the head or 0.4 m above or below it: the level rays graze its back, where the
    surface slope dr/dphi is huge. Its labelled echo must lie where the capsule is, between
    its near end (12 m - 0.7 m axis half-length - 0.2 m radius, from the head) and its far
    end, to within the range resolution; the quadratic range extremum once drew a streak
    of echo 4.5 m in front of it."""
    diver = dict(name="diver", kind="diver", initial_pos_ned=(12.3, 0.0, depth_m), initial_course_deg=0.0,
                 surge_mps=0.0, surge_sigma_mps=0.0, course_rate_sigma_dps=0.0, heave_sigma_mps=0.0,
                 reflectivity=0.9, bubbles={"enabled": False})
    scn = Scenario(name="along", duration_s=5.0, world={"seabed": {"depth_m": 30.0}, "movers": [diver]},
                   vehicle={"model": "bluerov2_heavy", "initial_pos_ned": (0.0, 0.0, 5.0)},
                   sensors={"fls": {"preset": "aris3000_lf", "tilt_deg": 0.0, "rate_hz": 6.0,
                                    "range_window_m": (1.0, 15.0), "mount_pos_body_m": (0.3, 0.0, 0.0)}})
    phys = Physics(scn)
    phys.reset(scn.vehicle.initial_pos_ned, (0.0, 0.0, 0.0))
    fls: FlsSensor = build_sensors({"fls": scn.sensors.fls}, phys.site_pos_body, 0)["fls"]
    truth = phys.truth()
    render = fls.measure(truth, phys.scene(), noise=False)
    head = truth.point_ned(fls.mount_pos_body_m)
    centre = np.array([12.3, 0.0, depth_m])
    # nearest and farthest points of the capsule (axis north-south, half-length 0.7, radius 0.2)
    axis = centre + np.outer(np.linspace(-0.7, 0.7, 1401), [1.0, 0.0, 0.0])
    dist = np.linalg.norm(axis - head, axis=1)
    near_m, far_m = dist.min() - 0.2, dist.max() + 0.2
    (obj,) = [o for o in render.truth.objects if o.name == "diver"]
    g = fls.geometry
    _, bins = np.nonzero(render.truth.mask_polar == obj.id)
    assert bins.size > 0
    rng_m = g.window_near_m + bins * g.range_resolution_m
    assert rng_m.min() >= near_m - 3 * g.range_resolution_m
    assert rng_m.max() <= far_m + 3 * g.range_resolution_m
    # the bright echo (the mean image, not only the labels) starts at the near end as well
    mean = render.mean_intensity
    beams_c = np.abs(g.beam_azimuths_rad()) < np.radians(3.0)
    strong = mean[beams_c] > 10 * np.median(mean)
    first = g.window_near_m + np.nonzero(strong.any(axis=0))[0].min() * g.range_resolution_m
    assert first >= near_m - 3 * g.range_resolution_m
