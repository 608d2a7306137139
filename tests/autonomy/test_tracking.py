"""Target tracker (paper 004): late USBL fixes re-processed at their measurement time, ROI
consistency over seeded runs, bad input, the ROI covariance and the kinematic Jacobian."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from scipy.stats import chi2

from autonomy.messages import UsblMsg
from autonomy.tracking import TargetKinematics, TargetTracker, TrackingConfig, polar_roi
from autonomy.tracking.kinematics import N_STATES

CFG = TrackingConfig(enabled=True, mode="fused", transponder="diver")


def _spherical(p_rel):
    x, y, z = p_rel
    return np.array([np.linalg.norm(p_rel), math.atan2(y, x), math.atan2(z, math.hypot(x, y))])


def _truth_path(t):
    """Target circling slowly; vehicle moving north at 0.2 m/s, heading 10 deg."""
    tgt = np.array([10.0 + 3.0 * math.sin(0.05 * t), 3.0 * math.cos(0.05 * t) - 3.0 + 0.1 * t, 5.0 + 0.01 * t])
    veh = np.array([0.2 * t, 0.0, 5.0])
    return tgt, veh, np.array([0.0, 0.0, math.radians(10.0)])


def _messages(seed=0, t_end=40.0):
    """(measurement time, delivery time, kind, payload) of USBL fixes every 2 s (late by
    0.3 s + travel) and sonar detections every 0.3 s (late by 0.05 s)."""
    rng = np.random.default_rng(seed)
    out = []
    for t in np.arange(0.5, t_end, 2.0):
        tgt, veh, rpy = _truth_path(t)
        R = _rot(rpy)
        z = _spherical(R.T @ (tgt - veh)) + rng.normal(0, [0.2, 0.02, 0.02])
        out.append((t, t + 0.3 + 2 * z[0] / 1500.0, "usbl", UsblMsg(t, *z, transponder="diver")))
    for t in np.arange(0.35, t_end, 0.3):
        tgt, veh, rpy = _truth_path(t)
        z = _spherical(_rot(rpy).T @ (tgt - veh)) + rng.normal(0, [0.05, 0.005, 0.0])
        out.append((t, t + 0.05, "sonar", (t, z[0], z[1])))
    return out


def _rot(rpy):
    from autonomy.frames import rot_from_euler
    return rot_from_euler(*rpy)


def _feed(tr, kind, payload):
    return tr.on_usbl(payload) if kind == "usbl" else tr.on_sonar(*payload)


def test_late_fixes_give_the_on_time_estimate():
    msgs = _messages()
    ticks = np.round(np.arange(0.0, 40.0 + 1e-9, 0.1), 10)
    late = TargetTracker(CFG)
    as_new = TargetTracker(CFG)
    for t in ticks:
        for tr in (late, as_new):
            tr.record_pose(t, *_truth_path(t)[1:])
        for tm, td, kind, payload in msgs:
            if t - 0.1 < td <= t:
                assert _feed(late, kind, payload)
                if kind == "usbl":  # the wrong way: stamped with the arrival tick
                    payload = UsblMsg(t, payload.range_m, payload.bearing_rad, payload.elevation_rad, "diver")
                else:
                    payload = (t, *payload[1:])
                _feed(as_new, kind, payload)
    on_time = TargetTracker(CFG)
    order = sorted(msgs, key=lambda m: m[0])
    k = 0
    for t in ticks:
        while k < len(order) and order[k][0] <= t:  # each measurement as soon as its time has come
            on_time.record_pose(order[k][0], *_truth_path(order[k][0])[1:])
            assert _feed(on_time, order[k][2], order[k][3])
            k += 1
        on_time.record_pose(t, *_truth_path(t)[1:])
    xa, Pa = late.estimate(40.0)
    xb, Pb = on_time.estimate(40.0)
    np.testing.assert_allclose(xa, xb, rtol=0, atol=1e-9)
    np.testing.assert_allclose(Pa, Pb, rtol=0, atol=1e-9)
    xc, _ = as_new.estimate(40.0)
    assert np.max(np.abs(xc - xb)) > 1e-3  # applying them as new is not the same filter
    assert late.used_counts()["usbl"] >= 3 and late.used_counts()["sonar"] > 20


@functools.lru_cache(maxsize=None)
def _simulate_consistent_run(seed, mode, t_end=40.0):
    """Truth drawn from the filter's own model (paper 004 eq. 6 with its process noise),
    measurements with its noise; returns per-step (roi contains truth, position NEES).
    The initiation's white acceleration is the surge noise plus the cross-track ``u^2 q_r t``
    of the course-rate walk over the first 10 s (0.3^2 * 0.001 * 10 ~ 0.001)."""
    rng = np.random.default_rng(seed)
    cfg = TrackingConfig(enabled=True, mode=mode, transponder="diver", course_rate_noise_rad2_per_s3=0.001,
                         surge_noise_m2_per_s3=0.002, heave_noise_m2_per_s3=0.0005, pos_noise_m2_per_s=0.001,
                         usbl_range_sigma_m=0.2, usbl_range_sigma_frac=0.0, usbl_angle_sigma_deg=1.5,
                         usbl_angle_sigma_deg_per_100m=0.0, target_size_m=0.0, target_thickness_m=0.0,
                         sonar_error_correlation_s=0.0,  # the synthetic sonar here: a point target, white noise
                         initiation_accel_noise_m2_per_s3=0.003, initial_surge_mps=0.0 if mode != "usbl" else 0.3,
                         initial_surge_sigma_mps=0.3 if mode != "usbl" else 0.1)
    kin = TargetKinematics(cfg.pos_noise_m2_per_s, cfg.course_rate_noise_rad2_per_s3, cfg.surge_noise_m2_per_s3,
                           cfg.heave_noise_m2_per_s3)
    q = np.array([cfg.pos_noise_m2_per_s] * 3 + [0.0, cfg.course_rate_noise_rad2_per_s3, cfg.surge_noise_m2_per_s3,
                                                 cfg.heave_noise_m2_per_s3])
    tr = TargetTracker(cfg)
    x = np.array([8.0, 0.0, 5.0, math.pi / 2, 0.0, 0.3, 0.0])
    veh, rpy = np.zeros(3) + [0, 0, 5.0], np.zeros(3)
    dt = 0.1
    sig_u = np.array([0.2, math.radians(1.5), math.radians(1.5)])
    sig_s = np.array([cfg.sonar_range_sigma_m, math.radians(cfg.sonar_azimuth_sigma_deg),
                      math.radians(cfg.sonar_vertical_beam_deg) / math.sqrt(12)])
    inside, nees = [], []
    for k in range(int(t_end / dt) + 1):
        t = k * dt
        if k > 0:
            x = kin.function(x, dt) + rng.standard_normal(N_STATES) * np.sqrt(q * dt)
        tr.record_pose(t, veh, rpy)
        z_true = _spherical(x[:3] - veh)
        if mode != "sonar" and k % 20 == 5:
            z = z_true + sig_u * rng.standard_normal(3)
            tr.on_usbl(UsblMsg(t, *z, transponder="diver"))
        if mode != "usbl" and (rng.random() < 0.3 or k == 0):
            z = z_true + sig_s * rng.standard_normal(3)
            tr.on_sonar(t, *z) if k else None
        if k == 0 and mode == "sonar":
            tr.on_sonar(t, *(z_true + sig_s * rng.standard_normal(3)))
        if t < 10.0 or not tr.initialised:
            continue
        xe, P = tr.estimate(t)
        e = x[:3] - xe[:3]
        nees.append(float(e @ np.linalg.solve(P[:3, :3], e)))
        roi = tr.roi(t)
        inside.append(bool(roi.contains(z_true[0], z_true[1])))
    return np.array(inside), np.array(nees)


@pytest.mark.parametrize("mode", ["fused"])  # the ROI steers the sonar detector only when fusing
def test_roi_contains_the_target_of_a_consistent_filter(mode):
    runs = [_simulate_consistent_run(seed, mode) for seed in range(50)]
    inside = np.concatenate([r[0] for r in runs])
    assert inside.mean() >= 0.95, inside.mean()


def test_position_nees_in_its_95_percent_band():
    """Mean position NEES over 50 runs, step by step, inside the chi-square(150) / 50 band at
    95 % in >= 90 % of the steps, and the grand mean within 10 % of 3 (no run diverges)."""
    nees = np.array([_simulate_consistent_run(seed, "fused")[1] for seed in range(50)])
    lo, hi = chi2.ppf([0.025, 0.975], 3 * 50) / 50
    in_band = np.mean((nees.mean(axis=0) >= lo) & (nees.mean(axis=0) <= hi))
    assert in_band >= 0.9, (in_band, nees.mean())
    assert abs(nees.mean() - 3.0) <= 0.3, nees.mean()
    assert nees.mean(axis=1).max() < 10.0


def test_course_model_takes_over_once_the_velocity_is_known():
    """A target crossing at 0.5 m/s east, fixed by USBL every 2 s: the constant-velocity start
    hands over to the course model, whose course converges to 90 deg and surge to 0.5 m/s."""
    cfg = TrackingConfig(enabled=True, mode="usbl", transponder="diver")
    tr = TargetTracker(cfg)
    rng = np.random.default_rng(3)
    for k in range(601):
        t = 0.1 * k
        tr.record_pose(t, [0.0, 0.0, 5.0], [0.0, 0.0, 0.0])
        if k % 20 == 0:
            z = _spherical(np.array([10.0, -10.0 + 0.5 * t, 2.0])) + rng.normal(0, [0.05, 0.005, 0.005])
            tr.on_usbl(UsblMsg(t, *z, transponder="diver"))
        if k == 20:
            assert not tr.course_known
    assert tr.course_known
    x, P = tr.estimate()
    assert abs(math.degrees(x[3]) - 90.0) < 3.0 and abs(x[5] - 0.5) < 0.03
    assert P.shape == (N_STATES, N_STATES)


def test_bad_input_is_refused_and_the_filter_keeps_running():
    tr = TargetTracker(CFG)
    for t in np.arange(0.0, 3.0, 0.1):
        tr.record_pose(t, [0.0, 0.0, 5.0], [0.0, 0.0, 0.0])
    assert tr.on_usbl(UsblMsg(1.0, 10.0, 0.1, 0.0, transponder="diver"))
    before = tr.estimate()[0].copy()
    assert not tr.on_usbl(UsblMsg(5.0, 10.0, 0.1, 0.0, transponder="diver"))  # from the future
    assert not tr.on_usbl(UsblMsg(2.0, float("nan"), 0.1, 0.0, transponder="diver"))
    assert not tr.on_usbl(UsblMsg(2.0, 10.0, 0.1, 0.0, transponder="nobody"))
    assert not tr.on_sonar(2.0, -1.0, 0.0)
    reasons = " | ".join(r for _, r in tr.rejected)
    assert "future" in reasons and "not finite" in reasons and "nobody" in reasons and len(tr.rejected) == 4
    np.testing.assert_array_equal(tr.estimate()[0], before)
    assert tr.on_usbl(UsblMsg(2.5, 10.1, 0.1, 0.0, transponder="diver"))  # and still takes good fixes
    assert tr.used_counts()["usbl"] == 2


def test_polar_roi_covariance_matches_monte_carlo():
    rng = np.random.default_rng(0)
    target = np.array([6.0, 3.0, 5.5])
    A = rng.normal(size=(3, 3)) * 0.02
    P = A @ A.T + 1e-4 * np.eye(3)
    head = np.array([0.5, 0.2, 5.0])
    R_ns = _rot([0.0, 0.0, math.radians(20.0)])
    roi = polar_roi(target, P, head, R_ns, 2.45, 0.0)
    pts = rng.multivariate_normal(target, P, size=200_000)
    rel = (pts - head) @ R_ns  # rows: R_ns^T (p - head)
    samples = np.stack([np.linalg.norm(rel, axis=1), np.arctan2(rel[:, 1], rel[:, 0])], axis=1)
    np.testing.assert_allclose(roi.covar_polar, np.cov(samples.T), rtol=0.03, atol=1e-8)
    assert roi.contains(*samples.T).mean() >= 0.95


def test_kinematics_jacobian_matches_finite_differences():
    kin = TargetKinematics(0.0, 0.0, 0.0, 0.0, max_step_s=1.0)
    x = np.array([1.0, 2.0, 3.0, 0.7, 0.05, 0.4, 0.02])
    x1, F = kin._step(x, 0.1)
    eps = 1e-7
    Fd = np.stack([(kin._step(x + eps * e, 0.1)[0] - kin._step(x - eps * e, 0.1)[0]) / (2 * eps)
                   for e in np.eye(N_STATES)], axis=1)
    np.testing.assert_allclose(F, Fd, atol=1e-8)
