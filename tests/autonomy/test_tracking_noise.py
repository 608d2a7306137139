"""Target tracker measurement noise: the sonar's near-side range offset, the
target-extent noise correlated from frame to frame, checked against hand computations and a
Monte Carlo of correlated detections."""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import chi2

from autonomy.messages import UsblMsg
from autonomy.tracking import TargetTracker, TrackingConfig


def _pose_tracker(cfg, yaw_rad=0.0, t_end=60.0):
    tr = TargetTracker(cfg)
    for t in np.round(np.arange(0.0, t_end + 1e-9, 0.1), 10):
        tr.record_pose(t, [0.0, 0.0, 5.0], [0.0, 0.0, yaw_rad])
    return tr


def test_sonar_range_is_taken_half_the_thickness_beyond_the_echo():
    """A sonar-only track started by one detection sits at range + thickness / 2 along its azimuth."""
    cfg = TrackingConfig(mode="sonar", target_thickness_m=0.4)
    tr = _pose_tracker(cfg, yaw_rad=math.radians(30.0), t_end=1.0)
    assert tr.on_sonar(0.5, 7.0, math.radians(10.0))
    x, _ = tr.estimate(0.5)
    bearing = math.radians(40.0)
    np.testing.assert_allclose(x[:3], [7.2 * math.cos(bearing), 7.2 * math.sin(bearing), 5.0], atol=1e-9)


def test_roi_is_centred_on_the_expected_echo():
    """The ROI's range centre is the estimated centre's range less half the thickness (the
    near side the detector sees); azimuth and half-widths are those of the covariance."""
    thin, thick = (TrackingConfig(mode="usbl", target_thickness_m=t) for t in (0.0, 0.4))
    rois = []
    for cfg in (thin, thick):
        tr = _pose_tracker(cfg, t_end=1.0)
        tr.on_usbl(UsblMsg(0.5, 8.0, math.radians(5.0), 0.0, "diver", True))
        rois.append(tr.roi(1.0))
    a, b = rois
    assert abs(a.range_m - 8.0) < 1e-6 and abs(b.range_m - (a.range_m - 0.2)) < 1e-12
    assert b.azimuth_rad == a.azimuth_rad and b.half_range_m == a.half_range_m


def test_second_detection_counts_as_correlated_extent_noise():
    """The second detection 1/6 s after the first updates as a Kalman update (hand algebra in
    the horizontal plane, polar Jacobian at the prior) with R = resolution^2 + the extent's
    uniform variance times (1 + rho) / (1 - rho), rho = exp(-dt / tau)."""
    cfg = TrackingConfig(mode="fused", target_thickness_m=0.4, target_size_m=1.0, sonar_error_correlation_s=10.0)
    tr = _pose_tracker(cfg, t_end=2.0)
    tr.on_usbl(UsblMsg(0.5, 8.0, 0.0, 0.0, "diver", True))
    tr.on_sonar(1.0, 7.75, math.radians(1.0))
    t2 = 1.0 + 1.0 / 6.0
    x0, P0 = tr.estimate(t2)
    z = np.array([7.9 + 0.2, math.radians(-0.5)])
    tr.on_sonar(t2, 7.9, math.radians(-0.5))
    x1, _ = tr.estimate(t2)
    rho = math.exp(-(1.0 / 6.0) / 10.0)
    k = (1.0 + rho) / (1.0 - rho)
    R = np.diag([0.1**2 + k * 0.4**2 / 12.0, math.radians(0.5) ** 2 + k * 1.0**2 / 12.0 / z[0] ** 2])
    n, e = x0[0], x0[1]
    r = math.hypot(n, e)
    H = np.array([[n / r, e / r], [-e / r**2, n / r**2]])
    P = P0[:2, :2]
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    expect = x0[:2] + K @ (z - [r, math.atan2(e, n)])
    np.testing.assert_allclose(x1[:2], expect, atol=1e-3)
    assert np.linalg.norm(x1[:2] - x0[:2]) > 1e-3  # it did update


def _correlated_run(seed, tau_model_s, t_end=30.0, tau_true_s=10.0):
    """A hovering target 8 m ahead; USBL every 2 s (white, the configured noise); sonar at
    6 Hz whose echo is the near side (range short by thickness / 2) and whose centre error is
    an AR(1) sequence (Gauss-Markov, ``tau_true_s``) with the extent's variance along and
    across the beam. Returns the horizontal position NEES after the first 10 s."""
    rng = np.random.default_rng(seed)
    cfg = TrackingConfig(mode="fused", target_thickness_m=0.4, target_size_m=1.0, sonar_error_correlation_s=tau_model_s,
                         usbl_range_sigma_frac=0.0, usbl_angle_sigma_deg_per_100m=0.0, initial_surge_mps=0.0,
                         initial_surge_sigma_mps=0.05)
    tgt = np.array([8.0, 0.0, 5.0])
    tr = TargetTracker(cfg)
    sig = np.array([0.4, 1.0]) / math.sqrt(12.0)
    b = sig * rng.standard_normal(2)
    dt, nees = 0.1, []
    for k in range(int(t_end / dt) + 1):
        t = k * dt
        tr.record_pose(t, [0.0, 0.0, 5.0], [0.0, 0.0, 0.0])
        if k % 20 == 0:
            z = np.array([8.0, 0.0, 0.0]) + [0.1, math.radians(1.0), math.radians(1.0)] * rng.standard_normal(3)
            tr.on_usbl(UsblMsg(t, *z, transponder="diver"))
        if k % 2 == 1 and k > 20:  # ~5 Hz sonar once the track stands
            rho = math.exp(-0.2 / tau_true_s)
            b = rho * b + math.sqrt(1.0 - rho**2) * sig * rng.standard_normal(2)
            r = 8.0 - 0.2 + b[0] + 0.1 * rng.standard_normal()
            tr.on_sonar(t, r, b[1] / 8.0 + math.radians(0.5) * rng.standard_normal())
        if t >= 10.0:
            x, P = tr.estimate(t)
            e = x[:2] - tgt[:2]
            nees.append(float(e @ np.linalg.solve(P[:2, :2], e)))
    return np.array(nees)


def test_correlated_extent_noise_keeps_the_filter_consistent():
    """Over 20 runs the horizontal NEES is not above its 2-D chi-square figures when the
    correlation is modelled (mean <= 2, at most 5 % of steps above the 95 % point; below 2
    because the hovering truth moves less than the filter's process noise allows), while
    treating the same detections as white makes the filter overconfident."""
    runs = 20
    modelled = np.array([_correlated_run(s, 10.0) for s in range(runs)])
    white = np.array([_correlated_run(s, 0.0) for s in range(runs)])
    p95 = chi2.ppf(0.95, 2)
    assert 0.8 <= modelled.mean() <= 2.0 and np.mean(modelled > p95) <= 0.05, (modelled.mean(), np.mean(modelled > p95))
    assert white.mean() > 3.0 and np.mean(white > p95) > 0.15, (white.mean(), np.mean(white > p95))
