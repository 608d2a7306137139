"""Ping360-class scanning sonar: device timing, sweep, raw pings against analytic geometry,
motion distortion, scan images and scenario validation."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.msis import ping360
from scenarios import ScenarioError, load_scenario
from scenarios.config.msis import MsisConfig
from sim.events.scheduler import SensorScheduler
from sim.sensors.analytic_caster import AnalyticBox, AnalyticCaster
from sim.sensors.msis import NO_ECHO_ID, WALL_ID, MsisSensor
from sim.sensors.msis_head import HeadSweep
from sim.sensors.msis_scan import ScanImage
from sim.sensors.registry import sensor_class


def _wall_north(n_m: float) -> AnalyticBox:
    """A vertical wall whose face is the plane north = n_m (background id, like basin walls)."""
    return AnalyticBox(np.array([n_m + 0.5, 0.0, 2.0]), np.array([0.5, 50.0, 5.0]), -1, 0.8)


def test_ping_timing_is_the_device_formula_worked_by_hand():
    cfg = MsisConfig(range_m=20.0, number_of_samples=1000, step_grad=2)
    # 2 * 20 / (1000 * 1500 * 25e-9) = 1066.67 ticks -> 1067
    assert cfg.sample_period_ticks == 1067
    assert cfg.sample_spacing_m == pytest.approx(1500 * 25e-9 * 1067 / 2)
    assert cfg.effective_range_m == pytest.approx(1000 * 1500 * 25e-9 * 1067 / 2)
    # automatic transmit: max(4000 * 20 / 1500 = 53.3 -> 53, 1.25 * 26.675) us
    assert cfg.effective_transmit_us == 53.0
    expected = 2 * 0.0025 + 53e-6 + 1000 * 1067 * 25e-9 + 0.004
    assert cfg.ping_duration_s == pytest.approx(expected, rel=1e-12)
    sensor = MsisSensor(cfg)
    assert sensor.rate_hz == pytest.approx(1.0 / expected)
    # the head takes longer for longer ranges
    assert MsisConfig(range_m=40.0).ping_duration_s > MsisConfig(range_m=10.0).ping_duration_s
    # fired by the scheduler on a 200 Hz physics clock for 10 s: one ping per ping duration
    sched = SensorScheduler(eps_s=0.25 / 200)
    sched.add("msis", sensor.rate_hz)
    fired = [k / 200 for k in range(1, 2001) if sched.due(k / 200)]
    assert abs(len(fired) - 10.0 / expected) <= 1.5
    assert np.mean(np.diff(fired)) == pytest.approx(expected, abs=0.5 / 200)


def test_transmit_duration_limits_follow_the_sample_period():
    # 64 sample periods at 80 ticks = 64 * 2 us = 128 us
    assert ping360.max_transmit_us(80) == pytest.approx(128.0)
    assert ping360.max_transmit_us(1000) == 500.0
    assert ping360.auto_transmit_us(2.0, 83, 1500.0) == pytest.approx(max(5.0, 1.25 * 83 * 0.025))


def test_sector_sweep_reverses_at_the_limits_and_a_full_turn_wraps():
    h = HeadSweep(step_grad=3, sector_width_grad=10, sector_centre_grad=0.0)
    got = [h.next_angle() for _ in range(12)]
    # sector [395, 405) -> offsets 0, 3, 6, 9, 10 (limit), 7, 4, 1, 0 (limit), 3, ...
    assert got == [395.0, 398.0, 1.0, 4.0, 5.0, 2.0, 399.0, 396.0, 395.0, 398.0, 1.0, 4.0]
    full = HeadSweep(step_grad=7, sector_width_grad=400, sector_centre_grad=100.0)
    angles = [full.next_angle() for _ in range(60)]
    assert angles[0] == 100.0 and np.all(np.mod(np.diff(angles), 400) == 7.0)


@pytest.mark.parametrize("dist_m", [3.0, 5.55, 7.3])
def test_ping_at_a_known_wall_distance_peaks_in_its_sample(dist_m):
    angle_grad = 0.0
    cfg = MsisConfig(range_m=10.0, speckle="none")
    sensor = MsisSensor(cfg)
    caster = AnalyticCaster(None, boxes=(_wall_north(dist_m),))
    r = sensor.render(0.0, angle_grad, np.array([0.0, 0.0, 1.0]), np.eye(3), caster, noise=False)
    # the beam axis meets the wall at dist / cos(angle); the vertical beam adds only longer ranges
    slant = dist_m / np.cos(ping360.grad_to_rad(angle_grad))
    k_wall = int(slant // sensor.sample_spacing_m)
    # the echo starts in the sample holding the wall and peaks there (or in the next one, when
    # the wall lies in the far part of its sample: the vertical beam fills the next one more)
    onset = int(np.flatnonzero(r.truth.mean_intensity > 1e-6 * r.truth.mean_intensity.max())[0])
    assert onset == k_wall
    k_peak = int(np.argmax(r.truth.mean_intensity))
    frac = slant / sensor.sample_spacing_m - k_wall
    assert k_peak == k_wall if frac < 0.5 else k_peak in (k_wall, k_wall + 1)
    assert r.truth.labels[k_peak] == WALL_ID
    assert np.all(r.truth.labels[:k_wall] == NO_ECHO_ID)
    assert r.ping.intensity.dtype == np.uint8 and r.ping.intensity.shape == (cfg.number_of_samples,)
    assert r.ping.intensity[k_peak] > r.ping.intensity[: k_peak - 20].max() + 100


def test_oblique_wall_peaks_inside_the_half_power_beam():
    sensor = MsisSensor(MsisConfig(range_m=10.0, speckle="none"))
    caster = AnalyticCaster(None, boxes=(_wall_north(5.0),))
    theta, half_bw = ping360.grad_to_rad(30.0), np.deg2rad(1.0)
    r = sensor.render(0.0, 30.0, np.array([0.0, 0.0, 1.0]), np.eye(3), caster, noise=False)
    k_peak = int(np.argmax(r.truth.mean_intensity))
    lo, hi = (5.0 / np.cos(theta + s * half_bw) / sensor.sample_spacing_m for s in (-1, 1))
    assert int(lo) <= k_peak <= int(hi)
    assert int(hi) - int(lo) >= 10  # the horizontal beam spreads an oblique wall over many samples


def test_facing_away_from_the_wall_the_ping_is_noise_only():
    sensor = MsisSensor(MsisConfig(range_m=10.0))
    caster = AnalyticCaster(None, boxes=(_wall_north(5.0),))
    r = sensor.render(0.0, 200.0, np.array([0.0, 0.0, 1.0]), np.eye(3), caster)
    assert np.all(r.truth.labels == NO_ECHO_ID) and r.ping.intensity.max() < 128


def _truth(t_s, pos, yaw=0.0):
    from autonomy.frames import rot_from_euler
    from sim.dynamics.truth import VehicleTruth

    return VehicleTruth(t_s, np.asarray(pos, float), rot_from_euler(0, 0, yaw), np.array([0, 0, yaw]),
                        np.zeros(6), np.zeros(6), np.zeros(3))


def _sweep_ping(sensor, truth, caster):
    """The next ping of the sweep, noise-free (the head steps)."""
    return sensor.render(truth.t_s, sensor.head.next_angle(), truth.point_ned(sensor.mount_pos_body_m), truth.R_nb,
                         caster, noise=False)


def _first_return_m(render, threshold=200):
    above = np.flatnonzero(render.ping.intensity >= threshold)
    return (above[0] + 0.5) * render.ping.sample_spacing_m if above.size else np.nan


def test_motion_during_a_turn_shifts_the_wall_by_the_distance_travelled():
    cfg = MsisConfig(range_m=10.0, step_grad=4, speckle="none")
    sensor = MsisSensor(cfg)
    caster = AnalyticCaster(None, boxes=(_wall_north(8.0),))
    v_mps, T = 0.3, cfg.ping_duration_s
    renders = [_sweep_ping(sensor, _truth(k * T, [v_mps * k * T, 0, 1.0]), caster) for k in range(101)]
    assert renders[0].ping.angle_grad == renders[100].ping.angle_grad == 0.0
    travelled = v_mps * 100 * T
    shift = _first_return_m(renders[0]) - _first_return_m(renders[100])
    assert shift == pytest.approx(travelled, abs=2 * sensor.sample_spacing_m)
    assert travelled > 0.5  # the distortion is much larger than a sample
    # the buffer places each echo with the pose of its own ping: the wall is straight again
    from autonomy.messages import NavEstimate
    from autonomy.msis.sonar_buffer import SonarBuffer

    buf, static = SonarBuffer(threshold_u8=200, max_age_s=60.0), SonarBuffer(threshold_u8=200, max_age_s=60.0)
    last = renders[-1].truth.pos_ned - sensor.mount_pos_body_m
    for r in renders:
        body = r.truth.pos_ned - sensor.mount_pos_body_m
        nav = NavEstimate(r.ping.t_s, body, np.zeros(3), np.array([v_mps, 0, 0]), np.zeros(3), np.eye(3))
        buf.add_ping(r.ping, nav)
        static.add_ping(r.ping, NavEstimate(r.ping.t_s, last, np.zeros(3), np.zeros(3), np.zeros(3), np.eye(3)))
    on_wall = lambda pts: pts[np.abs(pts[:, 1]) < 2.5]  # noqa: E731  (within ~17 deg of the wall normal)
    comp, raw = on_wall(buf.points_ne()), on_wall(static.points_ne())
    assert len(comp) >= 10
    # up to D tan(theta) half-beamwidth short at theta off the normal: the beam's near edge echoes first
    assert np.all(np.abs(comp[:, 0] - 8.0) < 0.05)
    assert np.ptp(raw[:, 0]) > 0.8 * travelled


def test_scan_image_places_the_wall_and_labels_its_pixels():
    cfg = MsisConfig(range_m=10.0, step_grad=2, speckle="none", scan_image_px=200)
    sensor = MsisSensor(cfg)
    caster = AnalyticCaster(None, boxes=(_wall_north(5.0),))
    scan = ScanImage.for_sensor(sensor)
    for k in range(200):
        scan.add(_sweep_ping(sensor, _truth(0.0, [0, 0, 1.0]), caster))
    assert len(scan.poses) == 200 and np.all(scan.polar_labels[:, 0] == NO_ECHO_ID)
    img, lab = scan.cartesian(), scan.cartesian_labels()
    c = 0.5 * (200 - 1)
    row_wall = int(round(c - 5.0 / scan.m_per_px))
    col = int(round(c))
    assert lab[row_wall - 1: row_wall + 2, col].tolist().count(WALL_ID) >= 1
    assert img[row_wall - 1: row_wall + 2, col].max() >= 200
    assert np.all(lab[row_wall + 3: int(c) - 2, col] == NO_ECHO_ID)  # water between head and wall
    # behind the head (south) there is no wall
    assert not np.any(lab[int(c) + 5:, col] == WALL_ID)


def test_measure_steps_the_head_and_an_exact_query_does_not():
    from sim.sensors.base import SceneView

    sensor = MsisSensor(MsisConfig(range_m=10.0, step_grad=5))
    scene = SceneView(0.0, AnalyticCaster(None, boxes=(_wall_north(5.0),)))
    angles = [sensor.measure(_truth(0.0, [0, 0, 1.0]), scene).ping.angle_grad for _ in range(3)]
    exact = sensor.measure(_truth(0.0, [0, 0, 1.0]), scene, noise=False)
    assert angles == [0.0, 5.0, 10.0] and exact.ping.angle_grad == 15.0
    assert sensor.measure(_truth(0.0, [0, 0, 1.0]), scene).ping.angle_grad == 15.0


def test_registered_by_kind():
    assert sensor_class("msis") is MsisSensor


@pytest.mark.parametrize("override, key, limit", [
    ("sensors.msis.sector_width_grad=401", r"sensors\.msis\.sector_width_grad", "400"),
    ("sensors.msis.step_grad=0", r"sensors\.msis\.step_grad", "1"),
    ("sensors.msis.number_of_samples=1300", r"sensors\.msis\.number_of_samples", "1200"),
    ("sensors.msis.range_m=1.0", r"range_m", ">= 80 ticks"),
    ("sensors.msis.range_m=60", r"sensors\.msis\.range_m", "50"),
])
def test_bad_device_settings_are_rejected_at_load_naming_key_and_limit(override, key, limit):
    with pytest.raises(ScenarioError, match=key) as err:
        load_scenario("cssn_lawnmower", ["sensors.msis.kind=msis", override])
    assert limit in str(err.value)
