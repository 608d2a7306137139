"""Tracking stack pieces: ROI scoring of detector clusters, the buddy observer's setpoints,
the constant-velocity -> course-model hand-over (against Stone Soup's Kalman filter)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.guidance.buddy import BuddyObserver
from autonomy.guidance.config import BuddyConfig
from autonomy.messages import Detection, NavEstimate, UsblMsg
from autonomy.tracking import TargetTracker, TrackingConfig
from autonomy.tracking.onboard import roi_score
from autonomy.tracking.roi import PolarRoi


def _det(r, a, score):
    return Detection(0.0, "diver", score, np.zeros(4), r, a)


def test_roi_score_keeps_inside_and_prefers_the_centre():
    roi = PolarRoi(8.0, 0.0, 1.0, math.radians(5.0), np.eye(2))
    dets = [_det(8.0, 0.0, 0.5), _det(8.9, math.radians(4.0), 0.9), _det(10.0, 0.0, 1.0), _det(8.0, -0.2, 1.0)]
    inside, s = roi_score(dets, roi)
    assert inside.tolist() == [True, True, False, False]
    d1 = math.hypot(0.9, 0.8) / math.sqrt(2.0)  # normalised distance of the second cluster
    np.testing.assert_allclose(s, [0.5, 0.9 * math.exp(-2.0 * d1**2), 0.0, 0.0], rtol=1e-12)
    assert np.argmax(s) == 0  # the weaker echo at the centre beats the stronger one at the edge
    inside, s = roi_score(dets, None)  # no estimate yet: every cluster, its own score
    assert inside.all() and s.tolist() == [0.5, 0.9, 1.0, 1.0]


def _nav(pos, yaw=0.0):
    return NavEstimate(0.0, np.asarray(pos, float), np.array([0.0, 0.0, yaw]), np.zeros(3), np.zeros(3), np.eye(3))


def test_buddy_observer_faces_closes_and_backs_off():
    cfg = BuddyConfig(enabled=True, behaviour="follow", distance_m=4.0, min_distance_m=1.5, gain_per_s=0.3,
                      max_speed_mps=0.6, depth_offset_m=0.5)
    b = BuddyObserver(cfg, initial_heading_rad=0.3, initial_depth_m=3.0)
    sp = b.update(_nav([0.0, 0.0, 3.0]), None)
    assert sp.speed_mps == 0.0 and sp.heading_rad == 0.3 and sp.depth_m == 3.0
    sp = b.update(_nav([1.0, 1.0, 3.0]), [4.0, 5.0, 6.0])  # 5 m away, bearing atan2(4, 3)
    assert sp.heading_rad == pytest.approx(math.atan2(4.0, 3.0))
    assert sp.speed_mps == pytest.approx(0.3 * (5.0 - 4.0)) and sp.depth_m == pytest.approx(5.5)
    assert b.update(_nav([0.0, 0.0, 3.0]), [30.0, 0.0, 5.0]).speed_mps == 0.6  # clipped
    assert b.update(_nav([0.0, 0.0, 3.0]), [1.0, 0.0, 5.0]).speed_mps == -0.6  # too close
    hold = BuddyObserver(cfg.model_copy(update={"behaviour": "hold"}), 0.0, 3.0)
    sp = hold.update(_nav([0.0, 0.0, 3.0]), [0.0, 10.0, 5.0])
    assert sp.speed_mps == 0.0 and sp.heading_rad == pytest.approx(math.pi / 2)
    hover = BuddyObserver(cfg.model_copy(update={"behaviour": "hover", "depth_m": 4.0}), 0.2, 3.0)
    sp = hover.update(_nav([0.0, 0.0, 3.0]), [0.0, 10.0, 5.0])
    assert (sp.speed_mps, sp.heading_rad, sp.depth_m) == (0.0, 0.2, 4.0)
    with pytest.raises(ValueError):
        b.update(_nav([0.0, 0.0, 3.0]), [np.nan, 0.0, 0.0])


def test_initiation_matches_stone_soup_kalman_filter():
    """Before the hand-over the tracker is a nearly-constant-velocity EKF: with USBL fixes from
    a head at the origin aligned with NED, its posterior equals Stone Soup's EKF (constant
    velocity per axis, same white-noise accelerations, elevation-bearing-range model)."""
    from datetime import datetime, timedelta

    from stonesoup.models.measurement.nonlinear import CartesianToElevationBearingRange
    from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                    ConstantVelocity)
    from stonesoup.predictor.kalman import ExtendedKalmanPredictor
    from stonesoup.types.detection import Detection as SsDetection
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.state import GaussianState
    from stonesoup.updater.kalman import ExtendedKalmanUpdater

    q_h, q_v = 0.006, 0.001
    cfg = TrackingConfig(enabled=True, mode="usbl", transponder="diver", initiation_accel_noise_m2_per_s3=q_h,
                         heave_noise_m2_per_s3=q_v, pos_noise_m2_per_s=0.0, initiation_course_sigma_deg=0.01,
                         usbl_range_sigma_frac=0.0, usbl_angle_sigma_deg_per_100m=0.0)
    tr = TargetTracker(cfg)
    rng = np.random.default_rng(1)
    fixes = []
    for k in range(4):
        t = 2.0 * k
        p = np.array([10.0 + 0.1 * t, 3.0 - 0.05 * t, 4.0])
        rng_m = np.linalg.norm(p)
        z = np.array([rng_m, math.atan2(p[1], p[0]), math.atan2(p[2], math.hypot(p[0], p[1]))])
        fixes.append((t, z + rng.normal(0, [0.1, 0.01, 0.01])))
    for k in range(61):
        tr.record_pose(0.1 * k, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    for t, z in fixes:
        assert tr.on_usbl(UsblMsg(t, *z, transponder="diver"))
    assert not tr.course_known
    x_ours = tr._last_state().mean  # (6,) CV state at the last fix
    P_ours = tr._last_state().covar

    # Stone Soup: state [n, vn, e, ve, d, vd]; measurement (elevation up > 0, bearing, range)
    order = [0, 3, 1, 4, 2, 5]
    sig_a = math.radians(cfg.usbl_angle_sigma_deg)
    R = np.diag([sig_a**2, sig_a**2, cfg.usbl_range_sigma_m**2])
    meas = CartesianToElevationBearingRange(ndim_state=6, mapping=(0, 2, 4), noise_covar=R)
    trans = CombinedLinearGaussianTransitionModel([ConstantVelocity(q_h), ConstantVelocity(q_h), ConstantVelocity(q_v)])
    t0 = datetime(2020, 1, 1)
    # the first fix initialises both: take our initial state as Stone Soup's prior
    first = TargetTracker(cfg)
    first.record_pose(0.0, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    first.on_usbl(UsblMsg(0.0, *fixes[0][1], transponder="diver"))
    x0, P0 = first._last_state().mean, first._last_state().covar
    state = GaussianState(x0[order].reshape(-1, 1), P0[np.ix_(order, order)], timestamp=t0)
    predictor, updater = ExtendedKalmanPredictor(trans), ExtendedKalmanUpdater(meas)
    for t, z in fixes[1:]:
        ts = t0 + timedelta(seconds=t)
        pred = predictor.predict(state, timestamp=ts)
        # on the NED state Stone Soup's atan2(z, rho) is our elevation (down > 0)
        det = SsDetection(np.array([[z[2]], [z[1]], [z[0]]]), timestamp=ts, measurement_model=meas)
        state = updater.update(SingleHypothesis(pred, det))
    inv = np.argsort(order)
    np.testing.assert_allclose(np.asarray(state.state_vector).ravel()[inv], x_ours, atol=1e-6)
    np.testing.assert_allclose(np.asarray(state.covar)[np.ix_(inv, inv)], P_ours, atol=1e-8)


def test_bubble_cluster_loses_to_the_diver_inside_the_roi():
    """Paper 004's contour detector on a synthetic fan: a diver's echo (1.8 m x 0.45 m) and,
    closer to the ROI centre and brighter, a breath's bubbles (five 0.14 m scatterers within
    0.6 m). Without the size gate the bubbles win the ROI; with it (the tracker's defaults)
    they are refused and the diver is chosen."""
    import cv2

    from autonomy.atr.classical import ClassicalDetector
    from autonomy.atr.config import ClassicalAtrConfig
    from autonomy.tracking.onboard import shape_gate

    mpp = 0.0275
    h, w = 480, 480
    rng = np.random.default_rng(3)
    fan = rng.rayleigh(25.0, (h, w))
    yy, xx = np.mgrid[0:h, 0:w]
    sonar_px = (w / 2.0, float(h))  # sonar head at the bottom centre, range up the image

    def px(x_m, y_m):  # metres right of and ahead of the head -> pixel
        return sonar_px[0] + x_m / mpp, sonar_px[1] - y_m / mpp

    dx, dy = px(-2.0, 8.0)
    diver = ((xx - dx) / (0.9 / mpp)) ** 2 + ((yy - dy) / (0.22 / mpp)) ** 2 <= 1.0
    fan[diver] = 140.0 + rng.normal(0.0, 20.0, int(diver.sum()))
    for bx, by in [(0.0, 8.3), (0.3, 8.1), (-0.2, 7.9), (0.25, 8.45), (0.05, 7.75)]:
        cx, cy = px(bx, by)
        fan[np.hypot(xx - cx, yy - cy) <= 0.07 / mpp] = 230.0
    fan = np.clip(fan, 0, 255).astype(np.uint8)
    fan = cv2.GaussianBlur(fan, (0, 0), 1.0)

    det = ClassicalDetector(ClassicalAtrConfig(), score_threshold=0.0)
    boxes, scores, feats = det.clusters(fan, mpp)
    cx, cy = 0.5 * (boxes[:, 0] + boxes[:, 2]), 0.5 * (boxes[:, 1] + boxes[:, 3])
    x_m, y_m = (cx - sonar_px[0]) * mpp, (sonar_px[1] - cy) * mpp
    dets = [_det(float(np.hypot(a, b)), float(math.atan2(a, b)), float(s)) for a, b, s in zip(x_m, y_m, scores)]
    is_diver = np.hypot(x_m + 2.0, y_m - 8.0) < 0.3
    is_bubble = np.hypot(x_m - 0.05, y_m - 8.1) < 0.5
    assert is_diver.sum() == 1 and is_bubble.any()

    roi = PolarRoi(8.1, math.atan2(0.05, 8.1), 1.5, math.radians(20.0), np.eye(2))  # both inside
    inside, s = roi_score(dets, roi)
    assert inside[is_diver].all() and inside[is_bubble].all()
    assert is_bubble[np.argmax(s)]  # the window and the detector's score alone pick the bubbles

    cfg = TrackingConfig()
    gate = shape_gate(feats, cfg.target_size_m, cfg.min_extent_frac, cfg.min_area_frac)
    assert gate[is_diver].all() and not gate[is_bubble].any()
    inside, s = roi_score(dets, roi, gate)
    assert is_diver[np.argmax(s)] and s[is_diver][0] >= cfg.detector_score_threshold


def test_diver_cut_by_the_fan_edge_passes_the_size_gate_but_bubbles_do_not():
    """A diver (1.8 m x 0.45 m, across the beam) whose centre lies 0.4 m outside the fan's port
    edge shows only a short piece: the size gate alone refuses it, but its contours reach the
    fan's boundary (``edge_gap_m`` about 0), so it is taken as cut by the edge (censored size)
    and kept, while a breath's bubbles in the middle of the fan stay refused."""
    from autonomy.atr.classical import ClassicalDetector, fan_edge_gap_m
    from autonomy.atr.config import ClassicalAtrConfig
    from autonomy.sonar_geometry import FanGeometry
    from autonomy.tracking.onboard import cut_by_edge, shape_gate

    geo = FanGeometry.fit(512, 512, 1.0, 15.0, math.radians(30.0))
    h, w = geo.height_px, geo.width_px
    yy, xx = np.mgrid[0:h, 0:w].astype(float)
    r, a = geo.pixel_to_polar(xx, yy)
    support = geo.inside(r, a)
    rng = np.random.default_rng(5)
    fan = rng.rayleigh(25.0, (h, w))
    x_m, y_m = r * np.sin(a), r * np.cos(a)  # starboard, ahead of the head
    edge_x = -8.0 * math.tan(math.radians(15.0))  # port edge at 8 m ahead
    diver = ((x_m - (edge_x - 0.4)) / 0.9) ** 2 + ((y_m - 8.0) / 0.22) ** 2 <= 1.0
    fan[diver] = 150.0 + rng.normal(0.0, 20.0, int(diver.sum()))
    for bx, by in [(0.0, 8.3), (0.3, 8.1), (-0.2, 7.9)]:
        fan[np.hypot(x_m - bx, y_m - by) <= 0.07] = 230.0
    fan = np.where(support, np.clip(fan, 0, 255), 0).astype(np.uint8)

    acfg = ClassicalAtrConfig()
    boxes, _, feats = ClassicalDetector(acfg, score_threshold=0.0).clusters(fan, geo.m_per_px, geometry=geo)
    cr, ca = geo.pixel_to_polar(0.5 * (boxes[:, 0] + boxes[:, 2]), 0.5 * (boxes[:, 1] + boxes[:, 3]))
    is_diver = (np.abs(cr - 8.0) < 0.4) & (ca < math.radians(-12.0))
    is_bubble = np.hypot(cr * np.sin(ca), cr * np.cos(ca) - 8.1) < 0.5
    assert is_diver.sum() == 1 and is_bubble.any()
    # the gap: analytic distance to the edge for points on it and inside
    on_edge = geo.polar_to_pixel(np.array([8.0]), np.array([-0.5 * geo.fov_rad]))
    assert fan_edge_gap_m(geo, *on_edge)[0] == pytest.approx(0.0, abs=1e-9)
    mid = geo.polar_to_pixel(np.array([8.0]), np.array([0.0]))
    assert fan_edge_gap_m(geo, *mid)[0] == pytest.approx(8.0 * math.sin(0.5 * geo.fov_rad), rel=1e-9)

    cfg = TrackingConfig()
    plain = shape_gate(feats, cfg.target_size_m, cfg.min_extent_frac, cfg.min_area_frac)
    assert not plain[is_diver].any() and not plain[is_bubble].any()
    cut = cut_by_edge(feats, acfg.blur_sigma_m + geo.m_per_px)
    assert cut[is_diver].all() and not cut[is_bubble].any()
    gate = shape_gate(feats, cfg.target_size_m, cfg.min_extent_frac, cfg.min_area_frac, cut)
    assert gate[is_diver].all() and not gate[is_bubble].any()


def test_polar_roi_outline_follows_its_range_and_azimuth_bounds():
    roi = PolarRoi(6.0, math.radians(5.0), 1.5, math.radians(4.0), np.eye(2))
    pts = roi.outline(8)
    assert pts.shape == (17, 2) and np.array_equal(pts[0], pts[-1])
    assert set(np.round(pts[:, 0], 12)) == {4.5, 7.5}
    assert pts[:, 1].min() == pytest.approx(math.radians(1.0)) and pts[:, 1].max() == pytest.approx(math.radians(9.0))
    assert roi.contains(pts[:, 0] * (1 - 1e-9) + 1e-9 * 6.0, pts[:, 1]).all()


def test_sonar_centre_sigma_widens_the_measurement_noise():
    """A detection whose centre is uncertain by ``centre_sigma_m`` moves the estimate less:
    the update equals a Kalman update with R + diag(c^2, c^2 / r^2) (independent algebra on
    the 2-D position), and a huge ``c`` leaves the prior (a point target: no extent terms)."""
    cfg = TrackingConfig(mode="fused", target_thickness_m=0.0, target_size_m=0.0)

    def run(c):
        tr = TargetTracker(cfg)
        tr.record_pose(0.0, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
        tr.on_usbl(UsblMsg(0.0, 8.0, 0.0, 0.0, "diver", True))
        prior = tr.estimate(0.0)
        tr.on_sonar(0.0, 8.3, math.radians(2.0), centre_sigma_m=c)
        return prior, tr.estimate(0.0)

    (x0, P0), (x1, _) = run(0.0)
    _, (x2, _) = run(0.5)
    _, (x3, _) = run(1e4)
    assert np.linalg.norm(x2[:2] - x0[:2]) < np.linalg.norm(x1[:2] - x0[:2])
    np.testing.assert_allclose(x3[:2], x0[:2], atol=1e-4)
    # independent check of the c = 0.5 update: linear KF in (n, e) with the polar Jacobian at the prior
    r0, a0 = 8.0, 0.0
    J = np.array([[1.0, 0.0], [0.0, 1.0 / r0]])  # d(range, azimuth)/d(n, e) at (8, 0)
    R = np.diag([cfg.sonar_range_sigma_m**2 + 0.25, math.radians(cfg.sonar_azimuth_sigma_deg) ** 2 + 0.25 / 8.3**2])
    P = P0[:2, :2]
    K = P @ J.T @ np.linalg.inv(J @ P @ J.T + R)
    expect = x0[:2] + K @ np.array([8.3 - r0, math.radians(2.0) - a0])
    np.testing.assert_allclose(x2[:2], expect, atol=2e-3)
