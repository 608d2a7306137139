"""Navigation sensors against analytic geometry, finite differences and their noise models."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError

from autonomy.frames import rot_from_euler, rot_y
from scenarios.config.nav_sensors import AltimeterConfig, DepthConfig, DvlConfig, GpsConfig, ImuConfig
from scenarios.schema import SensorsConfig
from sim.sensors.altimeter import AltimeterSensor
from sim.sensors.depth import DepthSensor
from sim.sensors.dvl import DvlSensor
from sim.sensors.gps import GpsSensor
from sim.sensors.imu import GRAVITY_MPS2, ImuSensor
from sim.sensors.base import SceneView
from sim.sensors.nav_noise import nav_noise_model
from sim.sensors.nav_suite import build_nav_sensors
from tests.support import PlaneCaster, flat_seabed, static_truth, wiggle_truth

RNG = np.random.default_rng
MOUNT = np.array([0.3, -0.1, 0.2])


# ----------------------------------------------------------------------------- DVL


@pytest.mark.parametrize("mount", [np.zeros(3), MOUNT])
def test_noise_free_dvl_equals_finite_differenced_position_in_body_frame(mount):
    dvl = DvlSensor(DvlConfig(), mount, RNG(0))
    caster = flat_seabed(20.0)
    h = 1e-4
    for t in np.linspace(0.0, 60.0, 13):
        tr = wiggle_truth(t)
        fd_ned = (wiggle_truth(t + h).point_ned(mount) - wiggle_truth(t - h).point_ned(mount)) / (2 * h)
        msg = dvl.measure(tr, SceneView(0.0, caster), noise=False)
        assert msg.valid
        np.testing.assert_allclose(msg.vel_body_mps, tr.R_nb.T @ fd_ned, atol=1e-7)
        assert msg.altitude_m == pytest.approx(20.0 - tr.point_ned(mount)[2], abs=1e-9)
        np.testing.assert_allclose(msg.beam_ranges_m * (dvl.beam_dirs_body @ tr.R_nb.T)[:, 2],
                                   20.0 - tr.point_ned(mount)[2], atol=1e-9)


def test_dvl_loses_lock_above_max_altitude():
    cfg = DvlConfig(max_altitude_m=30.0)
    dvl = DvlSensor(cfg, np.zeros(3), RNG(0))
    tr = static_truth(pos_ned=(0.0, 0.0, 5.0), rpy_rad=(0.0, 0.0, 1.0))
    assert dvl.measure(tr, SceneView(0.0, flat_seabed(5.0 + 29.0)), noise=False).valid
    lost = dvl.measure(tr, SceneView(0.0, flat_seabed(5.0 + 31.0)), noise=False)
    assert not lost.valid and np.all(np.isnan(lost.vel_body_mps)) and math.isnan(lost.altitude_m)


@pytest.mark.parametrize("slope_deg, locked", [(0.0, True), (20.0, True), (40.0, False), (60.0, False)])
def test_dvl_loses_lock_over_steep_slope(slope_deg, locked):
    dvl = DvlSensor(DvlConfig(max_slope_deg=30.0), np.zeros(3), RNG(0))
    normal = rot_y(math.radians(slope_deg)) @ np.array([0.0, 0.0, -1.0])  # seabed rising to the north
    caster = PlaneCaster([0.0, 0.0, 8.0], normal)
    tr = wiggle_truth(3.0)
    tr = type(tr)(t_s=tr.t_s, pos_ned=np.array([0.0, 0.0, 4.0]), R_nb=tr.R_nb, rpy_rad=tr.rpy_rad,
                  nu=tr.nu, nu_dot=tr.nu_dot, current_ned=tr.current_ned)
    msg = dvl.measure(tr, SceneView(0.0, caster), noise=False)
    assert msg.valid == locked
    if locked:
        np.testing.assert_allclose(msg.vel_body_mps, tr.nu[:3], atol=1e-9)


def test_dvl_noise_matches_filter_noise_model_and_dropout_rate():
    cfg = DvlConfig(dropout_prob=0.1, scale_error=0.0)
    dvl = DvlSensor(cfg, np.zeros(3), RNG(3))
    tr = static_truth(pos_ned=(0.0, 0.0, 2.0))
    tr = type(tr)(t_s=0.0, pos_ned=tr.pos_ned, R_nb=tr.R_nb, rpy_rad=tr.rpy_rad,
                  nu=np.array([0.8, 0.1, 0.05, 0.0, 0.0, 0.0]), nu_dot=np.zeros(6), current_ned=np.zeros(3))
    msgs = [dvl.measure(tr, SceneView(0.0, flat_seabed(10.0))) for _ in range(4000)]
    valid = np.array([m.valid for m in msgs])
    n = len(msgs)
    assert abs((~valid).mean() - 0.1) < 4 * math.sqrt(0.1 * 0.9 / n)
    vel = np.array([m.vel_body_mps for m in msgs if m.valid])
    expected = nav_noise_model(dvl=cfg).dvl_velocity_cov(tr.nu[:3])
    assert np.all(np.abs(vel.mean(axis=0) - tr.nu[:3]) < 4 * np.sqrt(np.diag(expected) / len(vel)))
    np.testing.assert_allclose(np.cov(vel.T), expected, rtol=0.1, atol=0.1 * expected.max())


def test_dvl_scale_error_spread_matches_config():
    cfg = DvlConfig(scale_error=0.01, beam_noise_mps=0.0, noise_frac_speed=0.0, dropout_prob=0.0)
    tr = type(static_truth())(t_s=0.0, pos_ned=np.array([0.0, 0.0, 2.0]), R_nb=np.eye(3), rpy_rad=np.zeros(3),
                              nu=np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), nu_dot=np.zeros(6), current_ned=np.zeros(3))
    scale = [DvlSensor(cfg, np.zeros(3), RNG(s)).measure(tr, SceneView(0.0, flat_seabed(9.0))).vel_body_mps[0] - 1.0
             for s in range(600)]
    assert np.std(scale) == pytest.approx(0.01, rel=0.12)


def test_ray_cast_sensors_require_a_caster():
    with pytest.raises(ValueError, match="RayCaster"):
        DvlSensor(DvlConfig(), np.zeros(3), RNG(0)).measure(static_truth())
    with pytest.raises(ValueError, match="RayCaster"):
        AltimeterSensor(AltimeterConfig(), np.zeros(3), RNG(0)).measure(static_truth())


# ----------------------------------------------------------------------------- IMU


@pytest.mark.parametrize("rpy", [(0.0, 0.0, 0.0), (0.0, 0.0, 2.0), (0.0, 0.5, 0.0), (0.3, -0.2, -1.0)])
def test_imu_at_rest_reads_gravity(rpy):
    imu = ImuSensor(ImuConfig(), MOUNT, RNG(0))
    msg = imu.measure(static_truth(rpy_rad=rpy), noise=False)
    np.testing.assert_allclose(msg.accel_body_mps2, rot_from_euler(*rpy).T @ [0.0, 0.0, -GRAVITY_MPS2], atol=1e-12)
    if rpy == (0.0, 0.0, 0.0):
        np.testing.assert_allclose(msg.accel_body_mps2, [0.0, 0.0, -9.81])
    np.testing.assert_allclose(msg.rpy_rad, rpy, atol=1e-12)
    np.testing.assert_allclose(msg.rate_body_radps, 0.0)


def test_imu_at_rest_with_noise_averages_to_gravity():
    cfg = ImuConfig()
    imu = ImuSensor(cfg, np.zeros(3), RNG(1))
    f = np.array([imu.measure(static_truth(t_s=0.01 * k)).accel_body_mps2 for k in range(2000)])
    bound = 5 * cfg.accel_bias_mps2 + 5 * cfg.accel_noise_mps2 / math.sqrt(len(f))
    np.testing.assert_allclose(f.mean(axis=0), [0.0, 0.0, -9.81], atol=bound)
    assert f[:, 2].std() == pytest.approx(cfg.accel_noise_mps2, rel=0.1)


def test_imu_specific_force_matches_finite_differenced_mount_acceleration():
    imu = ImuSensor(ImuConfig(), MOUNT, RNG(0))
    h = 1e-3
    for t in (1.0, 17.0, 33.3):
        tr = wiggle_truth(t)
        p = [wiggle_truth(t + k * h).point_ned(MOUNT) for k in (-1, 0, 1)]
        acc_ned = (p[2] - 2 * p[1] + p[0]) / h**2
        expected = tr.R_nb.T @ (acc_ned - [0.0, 0.0, GRAVITY_MPS2])
        np.testing.assert_allclose(imu.measure(tr, noise=False).accel_body_mps2, expected, atol=1e-5)


def test_fog_heading_error_is_bias_plus_random_walk():
    cfg = ImuConfig(heading_source="fog", fog_heading_bias_deg=0.5, fog_heading_noise_deg=0.0,
                    fog_heading_random_walk_deg_per_sqrt_h=60.0)  # 1 deg/sqrt(s) to see it quickly
    T = 9.0
    errs0, errsT = [], []
    for s in range(800):
        imu = ImuSensor(cfg, np.zeros(3), RNG(s))
        errs0.append(imu.measure(static_truth(t_s=0.0)).rpy_rad[2])
        errsT.append(imu.measure(static_truth(t_s=T)).rpy_rad[2])
    assert np.degrees(np.std(errs0)) == pytest.approx(0.5, rel=0.1)
    assert np.degrees(np.std(np.subtract(errsT, errs0))) == pytest.approx(math.sqrt(T), rel=0.1)


def test_ahrs_heading_option_uses_magnetic_noise():
    cfg = ImuConfig(heading_source="ahrs", ahrs_heading_noise_deg=2.0, ahrs_heading_bias_deg=0.0,
                    roll_pitch_bias_deg=0.0, roll_pitch_noise_deg=0.0)
    imu = ImuSensor(cfg, np.zeros(3), RNG(5))
    yaw = np.array([imu.measure(static_truth(t_s=0.1 * k, rpy_rad=(0, 0, 1.0))).rpy_rad for k in range(3000)])
    assert np.degrees(yaw[:, 2].std()) == pytest.approx(2.0, rel=0.08)
    np.testing.assert_allclose(yaw[:, :2], 0.0)


# ----------------------------------------------------------------------------- depth, altimeter, GPS


def test_depth_sensor_reads_mount_depth():
    tr = wiggle_truth(12.0)
    depth = DepthSensor(DepthConfig(noise_m=0.05), MOUNT, RNG(0))
    assert depth.measure(tr, noise=False).depth_m == pytest.approx(tr.point_ned(MOUNT)[2], abs=1e-12)
    samples = [depth.measure(tr).depth_m for _ in range(3000)]
    assert np.std(samples) == pytest.approx(0.05, rel=0.08)


def test_altimeter_measures_slant_range_and_range_limits():
    alt = AltimeterSensor(AltimeterConfig(max_range_m=30.0), np.zeros(3), RNG(0))
    tr = static_truth(pos_ned=(0.0, 0.0, 3.0), rpy_rad=(0.2, 0.1, 0.5))
    msg = alt.measure(tr, SceneView(0.0, flat_seabed(10.0)), noise=False)
    assert msg.valid and msg.altitude_m == pytest.approx(7.0 / (math.cos(0.2) * math.cos(0.1)))
    assert not alt.measure(tr, SceneView(0.0, flat_seabed(40.0)), noise=False).valid


def test_gps_fixes_only_at_the_surface():
    cfg = GpsConfig(max_antenna_depth_m=0.2, dropout_prob=0.0, noise_m=1.5)
    gps = GpsSensor(cfg, np.zeros(3), RNG(0))
    assert gps.measure(static_truth(pos_ned=(3.0, 4.0, 0.1)), noise=False).valid
    deep = gps.measure(static_truth(pos_ned=(3.0, 4.0, 0.5)))
    assert not deep.valid and np.all(np.isnan(deep.pos_ne_m))
    # antenna on a mast 0.5 m above the body origin: the antenna depth decides
    mast = GpsSensor(cfg, np.array([0.0, 0.0, -0.5]), RNG(0))
    assert mast.measure(static_truth(pos_ned=(0.0, 0.0, 0.6))).valid
    assert not mast.measure(static_truth(pos_ned=(0.0, 0.0, 0.8))).valid
    fixes = np.array([gps.measure(static_truth(pos_ned=(3.0, 4.0, 0.0))).pos_ne_m for _ in range(3000)])
    np.testing.assert_allclose(fixes.mean(axis=0), [3.0, 4.0], atol=0.15)
    np.testing.assert_allclose(fixes.std(axis=0), 1.5, rtol=0.08)


# ----------------------------------------------------------------------------- suite, determinism, config


MOUNTS = {"imu": np.zeros(3), "dvl": np.array([0.1, 0.0, 0.25]), "depth": np.zeros(3),
          "altimeter": np.array([0.2, 0.0, 0.25]), "gps": np.array([-0.1, 0.0, -0.4])}


def _run_suite(seed: int) -> list:
    sensors = build_nav_sensors(SensorsConfig(), MOUNTS, seed)
    caster = flat_seabed(12.0)
    out = []
    for t in np.arange(0.0, 5.0, 0.1):
        tr = wiggle_truth(t)
        for name, sensor in sensors.items():
            msg = sensor.measure(tr, SceneView(0.0, caster))
            out.append((name, msg))
    return out


def _flatten(msgs) -> np.ndarray:
    vals = []
    for _, m in msgs:
        for f in m.__slots__:
            vals.append(np.atleast_1d(np.asarray(getattr(m, f), dtype=float)))
    return np.concatenate(vals)


def test_suite_is_deterministic_for_a_fixed_seed():
    a, b, c = _flatten(_run_suite(7)), _flatten(_run_suite(7)), _flatten(_run_suite(8))
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(np.nan_to_num(a), np.nan_to_num(c))


def test_suite_builds_every_sensor_with_its_own_stream():
    sensors = build_nav_sensors(SensorsConfig(), MOUNTS, 0)
    assert set(sensors) == {"imu", "dvl", "depth", "altimeter", "gps"}
    assert all(s.name == k and s.rate_hz > 0 and s.latency_s(None) >= 0 for k, s in sensors.items())
    # the IMU stream does not depend on whether other sensors are used
    imu_alone = build_nav_sensors(SensorsConfig(), MOUNTS, 0)["imu"]
    tr = wiggle_truth(1.0)
    sensors["dvl"].measure(tr, SceneView(0.0, flat_seabed(12.0)))
    np.testing.assert_array_equal(sensors["imu"].measure(tr).rpy_rad, imu_alone.measure(tr).rpy_rad)


def test_suite_and_configs_reject_bad_input():
    with pytest.raises(ValueError, match="altimeter"):
        build_nav_sensors(SensorsConfig(), {k: v for k, v in MOUNTS.items() if k != "altimeter"}, 0)
    with pytest.raises(ValueError, match="gps"):
        build_nav_sensors(SensorsConfig(), {**MOUNTS, "gps": [0.0, 1.0]}, 0)
    with pytest.raises(ValidationError, match="max_slope_deg"):
        DvlConfig(max_slope_deg=100.0)
    with pytest.raises(ValidationError, match="heading_source"):
        ImuConfig(heading_source="compass")
    with pytest.raises(ValidationError, match="bogus"):
        GpsConfig(bogus=1.0)


@pytest.mark.parametrize("noise", [False, True])
def test_imu_message_does_not_share_or_change_the_truth_arrays(noise):
    imu = ImuSensor(ImuConfig(), MOUNT, RNG(3))
    tr = wiggle_truth(5.0)
    tr.rpy_rad[2] = 3.1  # near the wrap
    before = (tr.rpy_rad.copy(), tr.nu.copy())
    msg = imu.measure(tr, noise=noise)
    np.testing.assert_array_equal(tr.rpy_rad, before[0])
    np.testing.assert_array_equal(tr.nu, before[1])
    msg.rpy_rad[0] += 1.0
    msg.rate_body_radps[0] += 1.0
    np.testing.assert_array_equal(tr.rpy_rad, before[0])
    np.testing.assert_array_equal(tr.nu, before[1])
    assert -math.pi <= msg.rpy_rad[2] < math.pi


def test_dvl_plane_altitude_with_a_given_fit_equals_the_refit():
    from sim.sensors.dvl import _fitted_plane_ned, plane_altitude_m

    pts = np.array([[1.0, 0.5, 10.2], [-1.0, 0.4, 9.7], [0.2, -1.1, 10.0], [0.1, 1.3, 10.4]])
    origin = np.array([0.0, 0.0, 8.0])
    assert plane_altitude_m(pts, origin, _fitted_plane_ned(pts)) == plane_altitude_m(pts, origin)
