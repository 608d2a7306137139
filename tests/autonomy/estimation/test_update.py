"""Kalman updaters against a hand-computed case and Stone Soup; the gater against explicit
inverses, scipy's Gaussian density and the chi-square law."""

from __future__ import annotations

import datetime

import numpy as np
import pytest
from scipy.stats import chi2, multivariate_normal

from autonomy.estimation.gater import MahalanobisGater, innovation_log_likelihoods
from autonomy.estimation.measurement import PositionFix, RangeBearingElevation
from autonomy.estimation.updater import ExtendedKalmanUpdater, KalmanUpdater

T0 = datetime.datetime(2024, 1, 1)


def _random_spd(rng, n):
    A = rng.normal(size=(n, n))
    return A @ A.T + n * np.eye(n)


def test_scalar_kalman_update_by_hand():
    # prior N(0, 4), z = 2 with R = 1: K = 4/5, x = 1.6, P = 4 - 4 * 4/5 = 0.8
    x, P = KalmanUpdater(PositionFix(1, (0,), [[1.0]])).update([0.0], [[4.0]], [2.0])
    assert x[0] == pytest.approx(1.6) and P[0, 0] == pytest.approx(0.8)
    # an unmeasured, correlated component moves by its regression on the measured one
    x, P = KalmanUpdater(PositionFix(2, (0,), [[1.0]])).update([0.0, 0.0], [[4.0, 2.0], [2.0, 3.0]], [2.0])
    np.testing.assert_allclose(x, [1.6, 0.8])  # 2/5 * 2
    np.testing.assert_allclose(P, [[0.8, 0.4], [0.4, 3.0 - 4.0 / 5.0]])


def test_kalman_update_matches_stone_soup():
    pytest.importorskip("stonesoup")
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.types.detection import Detection
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.prediction import GaussianStatePrediction
    from stonesoup.updater.kalman import KalmanUpdater as SsUpdater

    rng = np.random.default_rng(0)
    for mapping in ((0, 1, 2), (0, 2), (3,)):
        x, P = rng.normal(size=4), _random_spd(rng, 4)
        R = _random_spd(rng, len(mapping))
        z = rng.normal(size=len(mapping))
        mean, covar = KalmanUpdater(PositionFix(4, mapping, R)).update(x, P, z)
        model = LinearGaussian(ndim_state=4, mapping=mapping, noise_covar=R)
        pred = GaussianStatePrediction(x[:, None], P, timestamp=T0)
        post = SsUpdater(model).update(SingleHypothesis(pred, Detection(z[:, None], timestamp=T0,
                                                                           measurement_model=model)))
        np.testing.assert_allclose(mean, np.asarray(post.state_vector, float).ravel(), rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(covar, np.asarray(post.covar, float), rtol=1e-9, atol=1e-12)


def test_extended_kalman_update_matches_stone_soup():
    pytest.importorskip("stonesoup")
    from stonesoup.models.measurement.nonlinear import CartesianToElevationBearingRange
    from stonesoup.types.detection import Detection
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.prediction import GaussianStatePrediction
    from stonesoup.updater.kalman import ExtendedKalmanUpdater as SsUpdater

    mount = np.array([0.2, 0.0, 0.4])
    x, P = np.array([15.0, -6.0, 4.0]), np.diag([2.0, 3.0, 1.0])
    model = RangeBearingElevation(mount, 0.3, 0.0, 0.02)
    z = np.array([16.5, -0.35, 0.22])
    R = model.covar(z[0])
    mean, covar = ExtendedKalmanUpdater(model).update(x, P, z, R)
    R_ss = R[::-1, ::-1]  # Stone Soup orders (elevation, bearing, range)
    ss_model = CartesianToElevationBearingRange(ndim_state=3, mapping=(0, 1, 2), noise_covar=R_ss,
                                                translation_offset=mount[:, None], rotation_offset=np.zeros((3, 1)))
    pred = GaussianStatePrediction(x[:, None], P, timestamp=T0)
    det = Detection(z[::-1, None], timestamp=T0, measurement_model=ss_model)
    post = SsUpdater(ss_model).update(SingleHypothesis(pred, det))
    # Stone Soup linearises with a numerical Jacobian: agreement to its step size
    np.testing.assert_allclose(mean, np.asarray(post.state_vector, float).ravel(), atol=1e-5)
    np.testing.assert_allclose(covar, np.asarray(post.covar, float), atol=1e-5)


def test_innovation_likelihoods_match_explicit_inverse_and_scipy():
    rng = np.random.default_rng(5)
    n, k = 4, 3
    X = rng.normal(size=(n, 3))
    P = np.stack([_random_spd(rng, 3) for _ in range(n)])
    Z = rng.normal(size=(k, 3))
    R = np.stack([_random_spd(rng, 3) * 0.1 for _ in range(k)])
    maha2, loglik = innovation_log_likelihoods(X, P, Z, R)
    for i in range(n):
        for j in range(k):
            S = P[i] + R[j]
            d = Z[j] - X[i]
            assert maha2[i, j] == pytest.approx(d @ np.linalg.inv(S) @ d, rel=1e-10)
            assert loglik[i, j] == pytest.approx(multivariate_normal(X[i], S).logpdf(Z[j]), rel=1e-10)


def test_chi_square_gate_keeps_the_stated_fraction_of_true_pairs():
    gate = MahalanobisGater.chi_square(0.99, 3)
    assert gate.threshold == pytest.approx(chi2.ppf(0.99, 3))
    assert MahalanobisGater.chi_square(0.999, 3).threshold == pytest.approx(16.27, abs=0.01)
    rng = np.random.default_rng(6)
    S = np.array([[2.0, 0.5, 0.0], [0.5, 1.0, 0.2], [0.0, 0.2, 0.5]])
    d = rng.multivariate_normal(np.zeros(3), S, size=20000)
    maha2, _ = innovation_log_likelihoods(np.zeros((1, 3)), (S - 0.1 * np.eye(3))[None], d,
                                          np.broadcast_to(0.1 * np.eye(3), (len(d), 3, 3)))
    kept = 1.0 - gate.rejects(maha2).mean()
    assert abs(kept - 0.99) < 4 * np.sqrt(0.99 * 0.01 / len(d))
    with pytest.raises(ValueError):
        MahalanobisGater(0.0)


@pytest.mark.parametrize("ndim_state, mapping", [(3, (0, 1, 2)), (6, (0, 1, 2)), (4, (3, 1))])
def test_batched_kalman_update_is_bit_identical_to_one_by_one(ndim_state, mapping):
    """update_batch row i == update(pair i) exactly (the world model relies on it)."""
    rng = np.random.default_rng(7)
    model = PositionFix(ndim_state, mapping)
    updater = KalmanUpdater(model)
    n, m = 200, len(mapping)
    scale = rng.uniform(1e-3, 10.0, (n, 1, 1))
    P = np.stack([_random_spd(rng, ndim_state) for _ in range(n)]) * scale
    R = np.stack([_random_spd(rng, m) for _ in range(n)]) * rng.uniform(1e-3, 10.0, (n, 1, 1))
    x = rng.normal(0.0, 50.0, (n, ndim_state))
    z = x[:, list(mapping)] + rng.normal(0.0, 1.0, (n, m))
    xb, Pb = updater.update_batch(x, P, z, R)
    for i in range(n):
        xi, Pi = updater.update(x[i], P[i], z[i], R[i])
        assert np.array_equal(xi, xb[i]) and np.array_equal(Pi, Pb[i])
    with pytest.raises(np.linalg.LinAlgError):
        updater.update_batch(x[:2], np.zeros((2, ndim_state, ndim_state)), z[:2], np.zeros((2, m, m)))


@pytest.mark.parametrize("ndim_state, mapping", [(3, (0, 1, 2)), (6, (0, 1, 2)), (4, (3, 1))])
def test_the_selection_update_is_the_general_update_with_a_selection_matrix(ndim_state, mapping):
    """KalmanUpdater (H by indexing) against kalman_update with H written out, and the
    information form of the posterior (P+^-1 = P^-1 + H^T R^-1 H) as an independent oracle."""
    from autonomy.estimation.updater import kalman_update

    rng = np.random.default_rng(11)
    model = PositionFix(ndim_state, mapping)
    H = np.zeros((len(mapping), ndim_state))
    H[np.arange(len(mapping)), list(mapping)] = 1.0
    for _ in range(20):
        P = _random_spd(rng, ndim_state)
        R = _random_spd(rng, len(mapping))
        x = rng.normal(0.0, 3.0, ndim_state)
        z = H @ x + rng.normal(0.0, 1.0, len(mapping))
        xa, Pa = KalmanUpdater(model).update(x, P, z, R)
        xb, Pb = kalman_update(x, P, z - H @ x, H, R)
        np.testing.assert_allclose(xa, xb, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(Pa, Pb, rtol=1e-10, atol=1e-12)
        info = np.linalg.inv(P) + H.T @ np.linalg.solve(R, H)
        np.testing.assert_allclose(Pb, np.linalg.inv(info), rtol=1e-8, atol=1e-10)
        x_info = np.linalg.solve(info, np.linalg.solve(P, x) + H.T @ np.linalg.solve(R, z))
        np.testing.assert_allclose(xb, x_info, rtol=1e-8, atol=1e-8)
