"""Navigation filter: Jacobians, exact dead reckoning, drift, NEES consistency, fixes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.stats import chi2

from autonomy.frames import rot_from_euler, wrap_angle
from autonomy.messages import DvlMsg, GpsMsg, ImuMsg, UsblMsg
from autonomy.navigation import NavigationFilter
from autonomy.navigation.config import NavigationConfig
from autonomy.navigation.ekf import rotated_vector_jacobian
from scenarios.schema import SensorsConfig
from sim.sensors.nav_suite import build_nav_sensors
from tests.support import NAV_MOUNTS, NAV_NOISE, SURVEY_TRUTHS, fly_filters


def _distance_m(truths) -> float:
    return float(sum(np.linalg.norm(b.pos_ned[:2] - a.pos_ned[:2]) for a, b in zip(truths, truths[1:])))


def _initial_pos(cfg: NavigationConfig, seed: int) -> np.ndarray:
    sigma = np.array([cfg.initial_pos_sigma_m, cfg.initial_pos_sigma_m, cfg.initial_depth_sigma_m])
    return SURVEY_TRUTHS[0].pos_ned + np.random.default_rng(10_000 + seed).standard_normal(3) * sigma


# ----------------------------------------------------------------------------- Jacobians


def test_rotated_vector_jacobian_matches_finite_differences():
    rng = np.random.default_rng(0)
    for _ in range(5):
        rpy, v = rng.uniform(-1.0, 1.0, 3), rng.normal(size=3)
        fd = np.column_stack([(rot_from_euler(*(rpy + h)) @ v - rot_from_euler(*(rpy - h)) @ v) / 2e-6
                              for h in 1e-6 * np.eye(3)])
        np.testing.assert_allclose(rotated_vector_jacobian(rpy, v), fd, atol=1e-8)


# ----------------------------------------------------------------------------- dead reckoning


def test_noise_free_sensors_dead_reckon_the_true_path():
    cfg = NavigationConfig(mode="dead_reckoning")
    sensors = build_nav_sensors(SensorsConfig(), NAV_MOUNTS, 0)
    f = NavigationFilter(cfg, SURVEY_TRUTHS[0].pos_ned, SURVEY_TRUTHS[0].rpy_rad[2], NAV_NOISE, mounts=NAV_MOUNTS)
    errs = [np.linalg.norm(est[0].pos_ned - tr.pos_ned) for tr, est in fly_filters([f], sensors, SURVEY_TRUTHS, 10, noise=False)]
    # only the zero-order hold of the 5 Hz DVL velocity separates the estimate from the truth
    assert max(errs) < 0.02
    est = f.estimate()
    np.testing.assert_allclose(wrap_angle(est.rpy_rad - SURVEY_TRUTHS[-1].rpy_rad), 0.0, atol=1e-4)
    np.testing.assert_allclose(est.vel_body_mps, SURVEY_TRUTHS[-1].nu[:3], atol=1e-3)


def test_dead_reckoning_drift_is_a_few_percent_of_distance():
    cfg = NavigationConfig(mode="dead_reckoning")
    distance = _distance_m(SURVEY_TRUTHS)
    drift, sigma = [], []
    for seed in range(6):
        sensors = build_nav_sensors(SensorsConfig(), NAV_MOUNTS, seed)
        f = NavigationFilter(cfg, SURVEY_TRUTHS[0].pos_ned, SURVEY_TRUTHS[0].rpy_rad[2], NAV_NOISE, mounts=NAV_MOUNTS)
        for _ in fly_filters([f], sensors, SURVEY_TRUTHS, len(SURVEY_TRUTHS)):
            pass
        est = f.estimate()
        drift.append(np.linalg.norm(est.pos_ned[:2] - SURVEY_TRUTHS[-1].pos_ned[:2]) / distance)
        sigma.append(np.sqrt(np.trace(est.cov_pos_ned[:2, :2])) / distance)
    # FeelHippo: about 3 % of the distance travelled; FOG + DVL defaults do better
    assert np.median(drift) < 0.03 and max(drift) < 0.05
    assert 0.002 < np.mean(sigma) < 0.03  # the covariance predicts drift of the same order
    assert np.mean(drift) > 0.0005  # noise is really there


def test_gps_is_ignored_in_dead_reckoning_and_gated_in_ekf():
    gps = GpsMsg(t_s=0.0, pos_ne_m=np.array([1.0, 0.0]), valid=True)
    dr = NavigationFilter(NavigationConfig(mode="dead_reckoning"), np.zeros(3), 0.0, NAV_NOISE)
    assert not dr.on_gps(gps)
    ekf = NavigationFilter(NavigationConfig(), np.zeros(3), 0.0, NAV_NOISE)
    cov_before = ekf.estimate().cov_pos_ned
    assert ekf.on_gps(gps)
    after = ekf.estimate()
    # scalar Kalman gain P / (P + R) with P = 1, R = 1
    assert after.pos_ned[0] == pytest.approx(0.5)
    assert after.cov_pos_ned[0, 0] == pytest.approx(cov_before[0, 0] / 2)
    assert not ekf.on_gps(GpsMsg(t_s=0.1, pos_ne_m=np.array([50.0, 0.0]), valid=True))  # outlier
    assert not ekf.on_gps(GpsMsg(t_s=0.2, pos_ne_m=np.full(2, np.nan), valid=False))


def test_lost_bottom_lock_inflates_covariance():
    cfg = NavigationConfig(mode="dead_reckoning", initial_pos_sigma_m=0.0, initial_depth_sigma_m=0.0)
    imu = ImuMsg(t_s=0.0, rpy_rad=np.zeros(3), rate_body_radps=np.zeros(3), accel_body_mps2=np.array([0, 0, -9.81]))
    locked, lost = (NavigationFilter(cfg, np.zeros(3), 0.0, NAV_NOISE) for _ in range(2))
    for k in range(1, 51):
        t = 0.2 * k
        good = DvlMsg(t_s=t, vel_body_mps=np.array([0.5, 0.0, 0.0]), valid=True, altitude_m=2.0,
                      beam_ranges_m=np.full(4, 2.3))
        bad = DvlMsg(t_s=t, vel_body_mps=np.full(3, np.nan), valid=False, altitude_m=np.nan)
        for f, msg in ((locked, good), (lost, good if k < 10 else bad)):
            f.on_imu(dataclasses.replace(imu, t_s=t))
            f.on_dvl(msg)
    assert locked.estimate().pos_ned[0] == pytest.approx(0.5 * 9.8, rel=1e-6)
    assert np.trace(lost.estimate().cov_pos_ned) > 10 * np.trace(locked.estimate().cov_pos_ned)


# ----------------------------------------------------------------------------- EKF consistency


def test_ekf_nees_within_chi_square_bounds_over_monte_carlo_runs():
    """Average position NEES over N seeded runs lies in the two-sided 95 % chi-square interval
    at (nearly) every checkpoint; a filter with over-optimistic noise fails the same check."""
    n_runs, every = 24, 50  # checkpoint every 10 s
    cfg = NavigationConfig()
    good_noise = NAV_NOISE
    bad_noise = dataclasses.replace(good_noise, attitude_bias_sigma_rad=good_noise.attitude_bias_sigma_rad / 4,
                                    dvl_scale_sigma=good_noise.dvl_scale_sigma / 4)
    nees = []
    for seed in range(n_runs):
        sensors = build_nav_sensors(SensorsConfig(), NAV_MOUNTS, seed)
        p0 = _initial_pos(cfg, seed)
        filters = [NavigationFilter(cfg, p0, SURVEY_TRUTHS[0].rpy_rad[2], n, mounts=NAV_MOUNTS) for n in (good_noise, bad_noise)]
        run = []
        for tr, ests in fly_filters(filters, sensors, SURVEY_TRUTHS, every):
            errs = [e.pos_ned - tr.pos_ned for e in ests]
            run.append([d @ np.linalg.solve(e.cov_pos_ned, d) for d, e in zip(errs, ests)])
        nees.append(run)
    anees = np.mean(nees, axis=0)  # (checkpoints, 2)
    lo, hi = chi2.ppf(0.025, 3 * n_runs) / n_runs, chi2.ppf(0.975, 3 * n_runs) / n_runs
    inside = (anees > lo) & (anees < hi)
    assert inside[:, 0].mean() >= 0.85, anees[:, 0]
    assert lo < anees[:, 0].mean() < hi
    assert inside[:, 1].mean() < 0.6 and anees[:, 1].mean() > hi


# ----------------------------------------------------------------------------- USBL


def test_usbl_fixes_pull_a_wrong_prior_to_the_truth():
    beacon = np.array([20.0, -10.0, 15.0])
    truth_pos, yaw = np.array([3.0, 4.0, 5.0]), 0.7
    cfg = NavigationConfig(initial_pos_sigma_m=5.0, initial_depth_sigma_m=5.0)
    f = NavigationFilter(cfg, truth_pos + [3.0, -2.0, 1.5], yaw, NAV_NOISE, usbl_beacon_pos_ned=beacon)
    R = rot_from_euler(0.0, 0.0, yaw)
    rng = np.random.default_rng(1)
    sig_a = np.radians(cfg.usbl_angle_noise_deg)
    for k in range(40):
        t = 0.5 * k
        f.on_imu(ImuMsg(t_s=t, rpy_rad=np.array([0.0, 0.0, yaw]), rate_body_radps=np.zeros(3),
                        accel_body_mps2=np.array([0.0, 0.0, -9.81])))
        f.on_dvl(DvlMsg(t_s=t, vel_body_mps=np.zeros(3), valid=True, altitude_m=5.0))
        x, y, z = R.T @ (beacon - truth_pos)  # beacon in FRD from the USBL head at the body origin
        r, b, e = np.sqrt(x * x + y * y + z * z), np.arctan2(y, x), np.arctan2(z, np.hypot(x, y))
        sig_r = cfg.usbl_range_noise_m + cfg.usbl_range_noise_frac * r
        f.on_usbl(UsblMsg(t_s=t, range_m=r + sig_r * rng.standard_normal(),
                          bearing_rad=b + sig_a * rng.standard_normal(), elevation_rad=e + sig_a * rng.standard_normal()))
    est = f.estimate()
    err = est.pos_ned - truth_pos
    assert np.linalg.norm(err) < 0.3
    assert err @ np.linalg.solve(est.cov_pos_ned, err) < chi2.ppf(0.999, 3)
    with pytest.raises(ValueError, match="usbl_beacon_pos_ned"):
        NavigationFilter(cfg, np.zeros(3), 0.0, NAV_NOISE).on_usbl(UsblMsg(t_s=0.0, range_m=1.0, bearing_rad=0.0, elevation_rad=0.0))


def test_altitude_refers_to_body_origin_not_the_sensor():
    """An altimeter 0.24 m below the body origin reads 0.24 m less than the body's altitude."""
    from autonomy.messages import AltimeterMsg

    mounts = {"altimeter": np.array([0.15, 0.0, 0.24]), "dvl": np.array([0.0, 0.0, 0.3])}
    f = NavigationFilter(NavigationConfig(), np.zeros(3), 0.0, NAV_NOISE, mounts=mounts)
    f.on_imu(ImuMsg(t_s=0.0, rpy_rad=np.zeros(3), rate_body_radps=np.zeros(3),
                    accel_body_mps2=np.array([0.0, 0.0, -9.81])))
    f.on_altimeter(AltimeterMsg(t_s=0.0, altitude_m=1.76, valid=True))
    assert f.estimate().altitude_m == pytest.approx(2.0)
    f.on_dvl(DvlMsg(t_s=0.1, vel_body_mps=np.zeros(3), valid=True, altitude_m=1.7))
    assert f.estimate().altitude_m == pytest.approx(2.0)
