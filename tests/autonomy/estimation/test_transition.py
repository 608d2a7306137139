"""Transition models and the Kalman predictor against analytic matrices and Stone Soup."""

from __future__ import annotations

import datetime

import numpy as np
import pytest

from autonomy.estimation.predictor import KalmanPredictor
from autonomy.estimation.transition import ConstantPosition, ConstantVelocity

EPOCH = datetime.datetime(2024, 1, 1)


def _td(dt_s: float) -> datetime.timedelta:
    return datetime.timedelta(seconds=dt_s)


def _random_spd(rng, n):
    A = rng.normal(size=(n, n))
    return A @ A.T + n * np.eye(n)


def test_constant_position_matches_stone_soup_random_walk():
    stonesoup_linear = pytest.importorskip("stonesoup.models.transition.linear")
    model = ConstantPosition(0.02, ndim=3)
    oracle = stonesoup_linear.CombinedLinearGaussianTransitionModel(
        [stonesoup_linear.RandomWalk(noise_diff_coeff=0.02)] * 3)
    for dt in (0.0, 0.3, 7.0):
        np.testing.assert_allclose(model.matrix(dt), oracle.matrix(time_interval=_td(dt)))
        np.testing.assert_allclose(model.covar(dt), oracle.covar(time_interval=_td(dt)), atol=1e-15)


def test_constant_velocity_matches_stone_soup():
    stonesoup_linear = pytest.importorskip("stonesoup.models.transition.linear")
    q, dt = 0.05, 0.8
    model = ConstantVelocity(q, ndim=3)
    oracle = stonesoup_linear.CombinedLinearGaussianTransitionModel(
        [stonesoup_linear.ConstantVelocity(noise_diff_coeff=q)] * 3)
    perm = [0, 2, 4, 1, 3, 5]  # Stone Soup interleaves (x, vx, y, vy, z, vz)
    F_ss = oracle.matrix(time_interval=_td(dt))[np.ix_(perm, perm)]
    Q_ss = oracle.covar(time_interval=_td(dt))[np.ix_(perm, perm)]
    np.testing.assert_allclose(model.matrix(dt), F_ss)
    np.testing.assert_allclose(model.covar(dt), Q_ss, rtol=1e-12)
    x = np.array([1.0, 2.0, 3.0, 0.5, -0.25, 0.1])
    np.testing.assert_allclose(model.function(x, dt), [1.4, 1.8, 3.08, 0.5, -0.25, 0.1])


def test_batched_covariance_propagation_equals_one_at_a_time():
    rng = np.random.default_rng(0)
    P = np.stack([_random_spd(rng, 3) for _ in range(5)])
    dt = rng.uniform(0.0, 3.0, 5)
    model = ConstantPosition(0.1)
    batch = model.propagate_covar(P, dt)
    for k in range(5):
        F = model.matrix(dt[k])
        np.testing.assert_allclose(batch[k], F @ P[k] @ F.T + model.covar(dt[k]), rtol=1e-14)
    cv = ConstantVelocity(0.2, ndim=2)
    P6 = _random_spd(rng, 4)
    F = cv.matrix(1.5)
    np.testing.assert_allclose(cv.propagate_covar(P6, 1.5), F @ P6 @ F.T + cv.covar(1.5))


def test_negative_or_nan_time_steps_are_rejected():
    for dt in (-0.1, float("nan")):
        with pytest.raises(ValueError, match="time step"):
            ConstantPosition(0.1).covar(dt)
    with pytest.raises(ValueError):
        ConstantVelocity(-1.0)


def test_predictor_matches_stone_soup_kalman_predictor():
    stonesoup_linear = pytest.importorskip("stonesoup.models.transition.linear")
    from stonesoup.predictor.kalman import KalmanPredictor as SsPredictor
    from stonesoup.types.state import GaussianState

    rng = np.random.default_rng(3)
    x, P, dt = rng.normal(size=4), _random_spd(rng, 4), 2.5
    cv = ConstantVelocity(0.3, ndim=2)
    mean, covar = KalmanPredictor(cv).predict(x, P, dt)
    ss_model = stonesoup_linear.CombinedLinearGaussianTransitionModel(
        [stonesoup_linear.ConstantVelocity(noise_diff_coeff=0.3)] * 2)
    perm = [0, 2, 1, 3]  # ours (x, y, vx, vy) -> Stone Soup (x, vx, y, vy)
    t0 = EPOCH
    prior = GaussianState(x[perm][:, None], P[np.ix_(perm, perm)], timestamp=t0)
    pred = SsPredictor(ss_model).predict(prior, timestamp=t0 + _td(dt))
    inv = np.argsort(perm)
    np.testing.assert_allclose(mean, np.asarray(pred.state_vector, float)[inv, 0])
    np.testing.assert_allclose(covar, np.asarray(pred.covar, float)[np.ix_(inv, inv)], rtol=1e-12)


def test_predictor_falls_back_to_the_fixed_gaussian_after_the_timeout():
    pred = KalmanPredictor(ConstantPosition(0.01), fallback_after_s=5.0, fallback_covar=2.0 * np.eye(3))
    P0 = 0.1 * np.eye(3)
    np.testing.assert_allclose(pred.predict_covar(P0, 4.0), 0.14 * np.eye(3))
    np.testing.assert_allclose(pred.predict_covar(P0, 6.0), 2.0 * np.eye(3))
    batch = pred.predict_covar(np.stack([P0, P0]), np.array([4.0, 6.0]))
    np.testing.assert_allclose(batch, [0.14 * np.eye(3), 2.0 * np.eye(3)])
    with pytest.raises(ValueError, match="both"):
        KalmanPredictor(ConstantPosition(0.01), fallback_after_s=5.0)

