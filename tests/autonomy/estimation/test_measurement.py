"""Measurement models: analytic values, finite-difference Jacobians, inverse(function(x)) == x,
and the USBL model against Stone Soup's elevation-bearing-range model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.estimation.measurement import PositionFix, RangeAzimuth, RangeBearingElevation


def _fd_jacobian(f, x, h=1e-6):
    x = np.asarray(x, float)
    return np.column_stack([(f(x + e) - f(x - e)) / (2 * h) for e in h * np.eye(x.size)])


def test_position_fix_is_the_selection_matrix():
    rng = np.random.default_rng(0)
    fix = PositionFix(6, (0, 1), 0.25 * np.eye(2))
    H = np.zeros((2, 6))
    H[0, 0] = H[1, 1] = 1.0
    x = rng.normal(size=6)
    P = rng.normal(size=(6, 6))
    np.testing.assert_array_equal(fix.matrix(), H)
    np.testing.assert_array_equal(fix.function(x), H @ x)
    np.testing.assert_array_equal(fix.project_covar(P), H @ P @ H.T)
    np.testing.assert_array_equal(fix.cross_covar(P), H @ P)
    np.testing.assert_array_equal(fix.inverse(fix.function(x)), H.T @ H @ x)
    full = PositionFix(3, (0, 1, 2))
    np.testing.assert_array_equal(full.inverse(full.function(x[:3])), x[:3])
    with pytest.raises(ValueError, match="noise_covar"):
        full.covar()
    with pytest.raises(ValueError, match="mapping"):
        PositionFix(3, (0, 3))


def test_range_bearing_elevation_analytic_values():
    model = RangeBearingElevation(mount_pos_m=(1.0, 0.0, 0.0))
    r, b, e = model.function([13.0, -5.0, 3.0])  # d = (12, -5, 3) from the head
    assert r == pytest.approx(math.sqrt(144 + 25 + 9))
    assert b == pytest.approx(math.atan2(-5.0, 12.0))  # port: negative
    assert e == pytest.approx(math.atan2(3.0, 13.0))  # below the head: positive
    np.testing.assert_allclose(model.function([1.0, 0.0, 5.0])[2], math.pi / 2)  # straight down


@pytest.mark.parametrize("model_cls", [RangeBearingElevation, RangeAzimuth])
def test_spherical_jacobians_match_finite_differences(model_cls):
    rng = np.random.default_rng(1)
    model = model_cls(mount_pos_m=(0.3, -0.1, 0.2))
    for _ in range(20):
        p = rng.uniform(-20, 20, 3)
        np.testing.assert_allclose(model.jacobian(p), _fd_jacobian(model.function, p), atol=1e-7)


def test_range_bearing_elevation_inverse_round_trips_with_its_jacobian():
    rng = np.random.default_rng(2)
    model = RangeBearingElevation(mount_pos_m=(0.5, 0.2, -0.3))
    for _ in range(20):
        p = rng.uniform(-30, 30, 3)
        z = model.function(p)
        np.testing.assert_allclose(model.inverse(z), p, atol=1e-12)
        J_inv = model.inverse_jacobian(z)
        np.testing.assert_allclose(J_inv, _fd_jacobian(model.inverse, z), atol=1e-6)
        np.testing.assert_allclose(model.jacobian(p) @ J_inv, np.eye(3), atol=1e-9)


def test_range_azimuth_inverse_needs_the_elevation():
    model = RangeAzimuth(mount_pos_m=(0.4, 0.0, 0.1))
    p = np.array([10.0, 3.0, 2.0])
    z = model.function(p)
    elevation = math.atan2(2.0 - 0.1, math.hypot(9.6, 3.0))
    np.testing.assert_allclose(model.inverse(z, elevation_rad=elevation), p, atol=1e-12)
    planar = model.inverse(z)  # paper 000 eq. 4: elevation zero, same slant range and azimuth
    assert planar[2] == pytest.approx(0.1)
    np.testing.assert_allclose(model.function(planar), z, atol=1e-12)
    J = model.inverse_jacobian(z, elevation)
    np.testing.assert_allclose(J, _fd_jacobian(lambda zz: model.inverse(zz, elevation), z), atol=1e-6)


def test_residuals_wrap_angles_only():
    model = RangeBearingElevation()
    res = model.residual([5.0, math.pi - 0.01, 0.2], [4.0, -math.pi + 0.01, 0.1])
    np.testing.assert_allclose(res, [1.0, -0.02, 0.1], atol=1e-12)
    res2 = RangeAzimuth().residual([5.0, -3.1], [5.5, 3.1])
    np.testing.assert_allclose(res2, [-0.5, 2 * math.pi - 6.2], atol=1e-12)


def test_usbl_noise_grows_with_range():
    model = RangeBearingElevation(range_sigma_m=0.1, range_sigma_frac=0.01, angle_sigma_rad=0.02)
    np.testing.assert_allclose(model.covar(50.0), np.diag([0.6**2, 0.02**2, 0.02**2]))


def test_range_bearing_elevation_matches_stone_soup():
    nonlinear = pytest.importorskip("stonesoup.models.measurement.nonlinear")
    from stonesoup.types.state import State

    mount = np.array([0.5, -0.2, 0.3])
    ours = RangeBearingElevation(mount_pos_m=mount)
    oracle = nonlinear.CartesianToElevationBearingRange(
        ndim_state=3, mapping=(0, 1, 2), noise_covar=np.eye(3), translation_offset=mount[:, None],
        rotation_offset=np.zeros((3, 1)))
    rng = np.random.default_rng(4)
    for _ in range(10):
        p = rng.uniform(-30, 30, 3)
        state = State(p[:, None])
        e, b, r = np.asarray(oracle.function(state), dtype=float).ravel()
        np.testing.assert_allclose(ours.function(p), [r, b, e], rtol=1e-12)
        np.testing.assert_allclose(ours.jacobian(p), np.asarray(oracle.jacobian(state), float)[::-1], atol=1e-6)
        np.testing.assert_allclose(ours.inverse([r, b, e]), np.asarray(oracle.inverse_function(
            State(np.array([[e], [b], [r]]))), float).ravel(), atol=1e-9)
