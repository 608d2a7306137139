"""Target geolocalisation (paper 000 eqs. 4-6) against hand-worked geometry."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.frames import rot_from_euler
from autonomy.localization import (
    flat_seabed_elevation,
    fls_visibility,
    localize,
    sonar_point_ned,
    sonar_to_body_rotation,
)
from autonomy.localization.config import LocalizationConfig
from autonomy.localization.sonar_projection import tilt_level_flat_seabed_elevation
from autonomy.messages import Detection, NavEstimate
from autonomy.sonar_geometry import FanGeometry


def _nav(pos=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0), altitude=float("nan"), cov_pos=0.0, cov_yaw=0.0):
    return NavEstimate(
        t_s=1.0, pos_ned=np.array(pos, float), rpy_rad=np.array(rpy, float),
        vel_body_mps=np.zeros(3), rate_body_radps=np.zeros(3),
        cov_pos_ned=cov_pos * np.eye(3), cov_yaw_rad2=cov_yaw, altitude_m=altitude,
    )


def _det(range_m, azimuth_rad, box=(100.0, 100.0, 120.0, 110.0)):
    return Detection(t_s=1.0, class_name="target", score=0.9, box_xyxy_px=np.array(box),
                     range_m=range_m, azimuth_rad=azimuth_rad)


def test_mount_tilt_points_boresight_down():
    b = sonar_to_body_rotation((0.0, np.deg2rad(30.0), 0.0)) @ np.array([1.0, 0.0, 0.0])
    np.testing.assert_allclose(b, [np.cos(np.pi / 6), 0.0, 0.5], atol=1e-12)


def test_planar_eq4_hand_worked():
    # Level vehicle heading east (yaw 90 deg), sonar 0.5 m ahead and 0.2 m below the origin,
    # no tilt. r = 10, a = +30 deg: sonar point (8.660, 5, 0); body (9.160, 5, 0.2);
    # NED = (-5, 9.160, 0.2) + vehicle position (1, 2, 3).
    cfg = LocalizationConfig(method="planar")
    loc = localize(_det(10.0, np.deg2rad(30.0)), _nav(pos=(1, 2, 3), rpy=(0, 0, np.pi / 2)),
                   (0.5, 0.0, 0.2), (0.0, 0.0, 0.0), cfg)
    np.testing.assert_allclose(loc.pos_ned, [1 - 5.0, 2 + 0.5 + 5 * np.sqrt(3), 3.2], atol=1e-9)
    assert loc.method == "planar"


def test_flat_seabed_eq5_eq6_hand_worked():
    # Level vehicle at 3 m altitude, sonar at the origin tilted 20 deg down, a = 0, r = 10:
    # eq. 5 sin(gamma + phi) = h / r; the point lies 3 m down and sqrt(100 - 9) m ahead.
    tilt, r, h = np.deg2rad(20.0), 10.0, 3.0
    phi = flat_seabed_elevation(r, 0.0, h, sonar_to_body_rotation((0, tilt, 0)))
    assert phi == pytest.approx(np.arcsin(0.3) - tilt, abs=1e-12)
    assert phi == pytest.approx(tilt_level_flat_seabed_elevation(r, h, tilt), abs=1e-12)
    cfg = LocalizationConfig(method="flat_seabed")
    loc = localize(_det(r, 0.0), _nav(pos=(0, 0, 2), altitude=h), (0, 0, 0), (0, tilt, 0), cfg)
    np.testing.assert_allclose(loc.pos_ned, [np.sqrt(91.0), 0.0, 5.0], atol=1e-9)
    # Off-boresight (a = 60 deg): the point still lies on the seabed at range r.
    loc = localize(_det(r, np.deg2rad(60)), _nav(pos=(0, 0, 2), altitude=h), (0, 0, 0),
                   (0, tilt, 0), cfg)
    assert loc.pos_ned[2] == pytest.approx(5.0, abs=1e-9)
    assert np.linalg.norm(loc.pos_ned - [0, 0, 2]) == pytest.approx(r, abs=1e-9)
    p_s = sonar_to_body_rotation((0, tilt, 0)).T @ (loc.pos_ned - [0, 0, 2])
    assert np.arctan2(p_s[1], p_s[0]) == pytest.approx(np.deg2rad(60), abs=1e-9)


def test_flat_seabed_recovers_seabed_point_with_attitude_and_lever_arm():
    pos, rpy = np.array([3.0, -2.0, 1.5]), np.array([0.03, -0.02, 0.7])
    mount, mount_rpy = np.array([0.4, 0.05, 0.25]), np.array([0.0, np.deg2rad(25.0), 0.0])
    seabed_z = 5.0
    R_nb = rot_from_euler(*rpy)
    R_ns = R_nb @ sonar_to_body_rotation(mount_rpy)
    head = pos + R_nb @ mount
    rng = np.random.default_rng(3)
    for _ in range(20):
        bearing = rpy[2] + rng.uniform(-1.0, 1.0)
        dist = rng.uniform(4.0, 25.0)
        target = np.array([head[0] + dist * np.cos(bearing), head[1] + dist * np.sin(bearing), seabed_z])
        p_s = R_ns.T @ (target - head)
        r, a = np.linalg.norm(p_s), np.arctan2(p_s[1], p_s[0])
        got = sonar_point_ned(r, a, pos, rpy, mount, mount_rpy, altitude_m=seabed_z - pos[2])
        np.testing.assert_allclose(got, target, atol=1e-9)


def test_flat_seabed_beats_planar_on_tilted_sonar_at_altitude():
    """Synthetic seabed returns seen by a 20-deg-tilted FLS at 3 m altitude (paper: 1.3 vs 2.5 m)."""
    rng = np.random.default_rng(0)
    tilt = np.deg2rad(20.0)
    pos, altitude = np.array([0.0, 0.0, 2.0]), 3.0
    err = {"flat_seabed": [], "planar": []}
    for _ in range(300):
        a = rng.uniform(-np.deg2rad(60), np.deg2rad(60))
        ground = rng.uniform(5.0, 30.0)  # horizontal distance
        target = pos + [ground * np.cos(a), ground * np.sin(a), altitude]
        rel = target - pos
        r = np.linalg.norm(rel) + rng.normal(0, 0.03)
        az = np.arctan2(rel[1], rel[0]) + rng.normal(0, 0.005)
        for method in err:
            loc = localize(_det(r, az), _nav(pos=pos, altitude=altitude + rng.normal(0, 0.05)),
                           (0, 0, 0), (0, tilt, 0), LocalizationConfig(method=method))
            err[method].append(np.linalg.norm(loc.pos_ned[:2] - target[:2]))
    flat, planar = np.mean(err["flat_seabed"]), np.mean(err["planar"])
    assert flat < 0.3  # noise only: 3 cm range, 5 mrad azimuth, 5 cm altitude
    assert planar > 3.0 * flat, (flat, planar)


def test_covariance_matches_monte_carlo():
    cfg = LocalizationConfig(range_sigma_m=0.1, azimuth_sigma_rad=0.01, altitude_sigma_m=0.1,
                             attitude_sigma_rad=0.01, tilt_sigma_rad=0.005, box_sigma_fraction=0.0,
                             min_sigma_m=0.0)
    pos, rpy, alt = np.array([1.0, 2.0, 1.0]), np.array([0.0, 0.0, 0.4]), 3.0
    mount, mount_rpy = np.array([0.5, 0.0, 0.2]), np.array([0.0, np.deg2rad(15), 0.0])
    cov_pos, cov_yaw = 0.04, np.deg2rad(1.0) ** 2
    r0, a0 = 12.0, 0.3
    loc = localize(_det(r0, a0), _nav(pos, rpy, alt, cov_pos, cov_yaw), mount, mount_rpy, cfg)
    rng = np.random.default_rng(1)
    n = 20000
    samples = np.empty((n, 3))
    for i in range(n):
        rpy_i = rpy + rng.normal(0, [0.01, 0.01, np.sqrt(cov_yaw)])
        samples[i] = sonar_point_ned(
            r0 + rng.normal(0, 0.1), a0 + rng.normal(0, 0.01), pos + rng.normal(0, 0.2, 3),
            rpy_i, mount, mount_rpy + [0, rng.normal(0, 0.005), 0],
            altitude_m=alt + rng.normal(0, 0.1),
        )
    emp = np.cov(samples.T)
    np.testing.assert_allclose(samples.mean(0), loc.pos_ned, atol=0.02)
    np.testing.assert_allclose(loc.cov_ned, emp, atol=0.1 * np.max(np.diag(emp)))
    assert np.all(np.abs(np.diag(loc.cov_ned) / np.diag(emp) - 1.0) < 0.1)


def test_box_extent_inflates_covariance_and_nan_altitude_falls_back():
    geom = FanGeometry.fit(894, 477, 1.0, 30.0, np.deg2rad(130))
    cfg = LocalizationConfig(box_sigma_fraction=0.3)
    nav = _nav(pos=(0, 0, 2), altitude=3.0)
    small = localize(_det(10.0, 0.1, (400, 200, 402, 202)), nav, (0, 0, 0), (0, 0.3, 0), cfg, geometry=geom)
    big = localize(_det(10.0, 0.1, (380, 180, 440, 230)), nav, (0, 0, 0), (0, 0.3, 0), cfg, geometry=geom)
    assert np.trace(big.cov_ned) > 2.0 * np.trace(small.cov_ned)
    fallback = localize(_det(10.0, 0.1), _nav(pos=(0, 0, 2)), (0, 0, 0), (0, 0.3, 0), cfg)
    assert fallback.method == "planar"


def test_fls_visibility_predicate():
    vis = fls_visibility((0, 0, 2), (0, 0, 0), (0.5, 0, 0), (0, 0.3, 0), range_min_m=1.0,
                         range_max_m=30.0, fov_rad=np.deg2rad(130))
    pts = np.array([[10.0, 0.0, 5.0], [-10.0, 0.0, 5.0], [50.0, 0.0, 5.0], [5.0, 20.0, 5.0]])
    np.testing.assert_array_equal(vis(pts), [True, False, False, False])


def test_batched_points_equal_the_scalar_chain():
    from autonomy.localization.geolocate import relative_points_ned

    rng = np.random.default_rng(3)
    mount = np.array([0.28, 0.05, 0.15])
    for use_seabed in (True, False):
        x = np.column_stack([rng.uniform(3, 30, 20), rng.uniform(-1, 1, 20), rng.uniform(1, 4, 20),
                             rng.normal(0, 0.05, (20, 2)), rng.uniform(-3, 3, 20), rng.uniform(0.1, 0.4, 20)])
        got = relative_points_ned(x, mount, 0.01, -0.02, use_seabed)
        for row, p in zip(x, got):
            want = sonar_point_ned(row[0], row[1], np.zeros(3), row[3:6], mount, (0.01, row[6], -0.02),
                                   altitude_m=row[2] if use_seabed else None)
            assert np.allclose(p, want, atol=1e-9)


def test_batched_rotations_bit_identical_to_stacked_form_and_equal_rot_from_euler():
    """``_rotations_zyx`` fills one (K, 3, 3) array; same bits as the stacked form it replaced
    (the speed-up left the localisation outputs unchanged) and equal to ``rot_from_euler`` per row."""
    from autonomy.localization.geolocate import _rotations_zyx

    rpy = np.random.default_rng(4).uniform(-np.pi, np.pi, (40, 3))
    cr, sr, cp, sp = np.cos(rpy[:, 0]), np.sin(rpy[:, 0]), np.cos(rpy[:, 1]), np.sin(rpy[:, 1])
    cy, sy = np.cos(rpy[:, 2]), np.sin(rpy[:, 2])
    stacked = np.stack([
        np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], axis=-1),
        np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], axis=-1),
        np.stack([-sp, cp * sr, cp * cr], axis=-1),
    ], axis=-2)
    got = _rotations_zyx(rpy)
    np.testing.assert_array_equal(got, stacked)
    for R, angles in zip(got, rpy):
        np.testing.assert_allclose(R, rot_from_euler(*angles), atol=1e-15)


def test_shared_part_is_the_navigation_and_reference_point_error():
    # The shared columns must reproduce, by Monte Carlo through the geometry itself, the error
    # a position and heading offset of the navigation solution makes (common to every
    # detection from that pose), plus the configured reference-point floor.
    cfg = LocalizationConfig(box_sigma_fraction=0.0, min_sigma_m=0.15)
    pos, rpy, alt = np.array([1.0, 2.0, 1.0]), np.array([0.0, 0.0, 0.4]), 3.0
    mount, mount_rpy = np.array([0.5, 0.0, 0.2]), np.array([0.0, np.deg2rad(15), 0.0])
    cov_pos, cov_yaw = 0.04, np.deg2rad(1.0) ** 2
    loc = localize(_det(12.0, 0.3), _nav(pos, rpy, alt, cov_pos, cov_yaw), mount, mount_rpy, cfg)
    L = loc.shared_ned
    assert L.shape == (3, 7)
    np.testing.assert_allclose(L[:, :3] @ L[:, :3].T, cov_pos * np.eye(3), atol=1e-12)
    np.testing.assert_allclose(L[:, 4:], 0.15 * np.eye(3))
    rng = np.random.default_rng(2)
    dyaw = rng.normal(0, np.sqrt(cov_yaw), 4000)
    pts = np.array([sonar_point_ned(12.0, 0.3, pos, rpy + [0, 0, d], mount, mount_rpy, altitude_m=alt) for d in dyaw])
    np.testing.assert_allclose(np.outer(L[:, 3], L[:, 3]), np.cov(pts.T), atol=2e-4)
    # the rest of the covariance is the per-frame part: positive semi-definite, and without
    # navigation or floor terms the same detection has no shared part at all
    assert np.linalg.eigvalsh(loc.cov_ned - L @ L.T).min() > -1e-12
    bare = localize(_det(12.0, 0.3), _nav(pos, rpy, alt), mount, mount_rpy,
                    LocalizationConfig(box_sigma_fraction=0.0, min_sigma_m=0.0))
    assert not bare.shared_ned.any()
