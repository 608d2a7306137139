"""USBL sensor: sample statistics of 5000 fixes against the configured noise model, outlier and
dropout rates, latency, and the fix of a moving transponder at capture time."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from autonomy.frames import rot_from_euler
from scenarios.config.usbl import UsblConfig
from sim.sensors.base import Mount, SceneView
from sim.sensors.usbl import UsblSensor
from sim.dynamics.truth import VehicleTruth

N_FIXES = 5000


def _truth(pos_ned, rpy, t_s=0.0) -> VehicleTruth:
    rpy = np.asarray(rpy, float)
    return VehicleTruth(t_s=t_s, pos_ned=np.asarray(pos_ned, float), R_nb=rot_from_euler(*rpy), rpy_rad=rpy,
                        nu=np.zeros(6), nu_dot=np.zeros(6), current_ned=np.zeros(3))


def _scene(p_ned, name="diver", t_s=0.0) -> SceneView:
    obj = SimpleNamespace(id=0, name=name, class_name="diver", is_target=True, centroid_ned=np.asarray(p_ned, float))
    return SceneView(t_s, None, (obj,))


def _geometry():
    """Vehicle at (1, 2, 3) heading 30 deg; head 0.5 m forward, 0.2 m down; target 40 m away."""
    truth = _truth([1.0, 2.0, 3.0], [0.0, 0.0, np.radians(30.0)])
    mount = Mount(np.array([0.5, 0.0, 0.2]))
    target = np.array([1.0 + 30.0, 2.0 + 25.0, 3.0 + 8.0])
    head = truth.point_ned(mount.pos_body_m)
    d_body = truth.R_nb.T @ (target - head)
    r = np.linalg.norm(d_body)
    # independent spherical coordinates (not the measurement model under test)
    expected = np.array([r, np.arctan2(d_body[1], d_body[0]), np.arcsin(d_body[2] / r)])
    return truth, mount, target, expected


def test_fix_statistics_match_the_configured_model():
    cfg = UsblConfig(transponder="diver", outlier_prob=0.0, dropout_prob=0.0, range_sigma_m=0.2,
                     range_sigma_frac=0.02, angle_sigma_deg=1.5, angle_sigma_deg_per_100m=2.0)
    truth, mount, target, expected = _geometry()
    sensor = UsblSensor(cfg, mount, np.random.default_rng(7))
    scene = _scene(target)
    z = np.array([[m.range_m, m.bearing_rad, m.elevation_rad] for m in
                  (sensor.measure(truth, scene) for _ in range(N_FIXES))])
    exact = sensor.measure(truth, scene, noise=False)
    np.testing.assert_allclose([exact.range_m, exact.bearing_rad, exact.elevation_rad], expected, atol=1e-12)
    r = expected[0]
    sigma = np.array([0.2 + 0.02 * r, np.radians(1.5 + 2.0 * r / 100.0), np.radians(1.5 + 2.0 * r / 100.0)])
    err = (z - expected) / sigma
    # mean within 4 standard errors; variance within the 99.99 % chi-square interval
    assert np.all(np.abs(err.mean(axis=0)) < 4.0 / np.sqrt(N_FIXES))
    lo, hi = stats.chi2.ppf([5e-5, 1 - 5e-5], N_FIXES - 1) / (N_FIXES - 1)
    var = err.var(axis=0, ddof=1)
    assert np.all((var > lo) & (var < hi)), var
    for k in range(3):  # Gaussian shape
        assert stats.kstest(err[:, k], "norm").pvalue > 1e-3


def test_outliers_and_dropouts_at_their_rates():
    cfg = UsblConfig(transponder="diver", outlier_prob=0.1, dropout_prob=0.2, outlier_extra_range_m=10.0,
                     range_sigma_m=0.05, range_sigma_frac=0.0)
    truth, mount, target, expected = _geometry()
    sensor = UsblSensor(cfg, mount, np.random.default_rng(3))
    msgs = [sensor.measure(truth, _scene(target)) for _ in range(N_FIXES)]
    valid = np.array([m.valid for m in msgs])
    p_drop = 1.0 - valid.mean()
    assert abs(p_drop - 0.2) < 4 * np.sqrt(0.2 * 0.8 / N_FIXES)
    assert all(np.isnan(m.range_m) for m in msgs if not m.valid)
    dr = np.array([m.range_m for m in msgs if m.valid]) - expected[0]
    far = np.mean(dr > 6 * 0.05)  # outliers: range longer by U(0, 10 m); P(U < 0.3 m) = 3 %
    p_far = 0.1 * (1 - 0.3 / 10.0)
    assert abs(far - p_far) < 4 * np.sqrt(p_far * (1 - p_far) / valid.sum())
    assert dr.min() > -6 * 0.05  # multipath never shortens the path


def test_latency_is_processing_plus_two_way_travel_time():
    cfg = UsblConfig(transponder="diver", latency_s=0.3, turnaround_s=0.1, sound_speed_mps=1500.0)
    truth, mount, target, expected = _geometry()
    sensor = UsblSensor(cfg, mount, np.random.default_rng(0))
    msg = sensor.measure(truth, _scene(target), noise=False)
    assert sensor.latency_s(msg) == pytest.approx(0.4 + 2.0 * expected[0] / 1500.0, abs=1e-12)
    assert msg.t_s == truth.t_s  # the fix carries its measurement time


def test_beacon_and_missing_transponder():
    cfg = UsblConfig(beacon_pos_ned=(10.0, 0.0, 5.0), dropout_prob=0.0)
    sensor = UsblSensor(cfg, np.zeros(3), np.random.default_rng(0))
    msg = sensor.measure(_truth([0, 0, 5.0], [0, 0, 0]), noise=False)
    assert msg.transponder == "beacon" and msg.range_m == pytest.approx(10.0) and msg.bearing_rad == pytest.approx(0.0)
    other = UsblSensor(UsblConfig(transponder="nobody"), np.zeros(3), np.random.default_rng(0))
    with pytest.raises(ValueError, match="nobody"):
        other.measure(_truth([0, 0, 0], [0, 0, 0]), _scene([1, 0, 0]))
    assert UsblConfig().beacon_pos_ned == (0.0, 0.0, 0.0)  # default: a beacon at the mission origin


def test_same_seed_same_fixes():
    cfg = UsblConfig(transponder="diver")
    truth, mount, target, _ = _geometry()
    a = [UsblSensor(cfg, mount, np.random.default_rng(5)).measure(truth, _scene(target)) for _ in range(3)]
    b = [UsblSensor(cfg, mount, np.random.default_rng(5)).measure(truth, _scene(target)) for _ in range(3)]
    assert [m.range_m for m in a] == [m.range_m for m in b]
