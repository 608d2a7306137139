"""Schmidt consider update against closed forms and Monte Carlo truth (not its own output)."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.estimation.measurement import PositionFix
from autonomy.estimation.updater import ConsiderKalmanUpdater, KalmanUpdater

FIX = PositionFix(3, (0, 1, 2))


def _spd(rng, n=3, scale=1.0):
    a = rng.normal(size=(n, n))
    return scale * (a @ a.T + n * np.eye(n))


def test_without_shared_errors_it_is_the_kalman_update():
    rng = np.random.default_rng(0)
    x, P, z, R = rng.normal(size=3), _spd(rng), rng.normal(size=3), _spd(rng, scale=0.3)
    q = 7
    xs, Ps, Ms = ConsiderKalmanUpdater(FIX).update_consider(x, P, np.zeros((3, q)), z, R, np.zeros((3, q)))
    xk, Pk = KalmanUpdater(FIX).update(x, P, z, R)
    np.testing.assert_allclose(xs, xk, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(Ps, Pk, rtol=1e-12, atol=1e-12)
    assert not Ms.any()


@pytest.mark.parametrize("n", [2, 10, 200])
def test_a_shared_bias_never_averages_out(n):
    # z_k = x + l u + v_k, v_k ~ N(0, s^2 I) independent, u ~ N(0, I) shared: the best estimate
    # from n looks is their mean, with variance l^2 + s^2 / n per axis (closed form).
    rng = np.random.default_rng(n)
    l_m, s_m = 0.3, 0.5
    L = l_m * np.eye(3)
    R = (s_m**2 + l_m**2) * np.eye(3)
    zs = rng.normal(size=(n, 3))
    up = ConsiderKalmanUpdater(FIX)
    x, P, M = zs[0].copy(), R.copy(), L.copy()  # born from the first look
    for z in zs[1:]:
        x, P, M = up.update_consider(x, P, M, z, R, L)
    np.testing.assert_allclose(x, zs.mean(axis=0), atol=1e-12)
    np.testing.assert_allclose(P, (l_m**2 + s_m**2 / n) * np.eye(3), atol=1e-12)
    np.testing.assert_allclose(M, L, atol=1e-12)
    # the plain Kalman filter takes the bias for noise and shrinks below it
    xk, Pk = zs[0].copy(), R.copy()
    for z in zs[1:]:
        xk, Pk = KalmanUpdater(FIX).update(xk, Pk, z, R)
    np.testing.assert_allclose(Pk, (l_m**2 + s_m**2) / n * np.eye(3), atol=1e-12)


def test_nees_is_chi_square_when_the_shared_error_drifts():
    # Monte Carlo: the shared error's sensitivity L_k changes from look to look (a navigation
    # solution whose covariance grows and turns), u is one draw per run. The consider filter's
    # mean 3-D NEES must be 3 (chi-square, 3 dof); the plain filter's far above.
    rng = np.random.default_rng(7)
    runs, looks, q = 1500, 25, 4
    up = ConsiderKalmanUpdater(FIX)
    nees_c, nees_k = [], []
    for _ in range(runs):
        x_true = rng.normal(size=3) * 5
        u = rng.normal(size=q)
        A, B = rng.normal(scale=0.25, size=(3, q)), rng.normal(scale=0.01, size=(3, q))
        Ls = [A + k * B for k in range(looks)]
        Rv = [np.diag(rng.uniform(0.01, 0.09, 3)) for _ in range(looks)]
        zs = [x_true + L @ u + rng.multivariate_normal(np.zeros(3), R) for L, R in zip(Ls, Rv)]
        Rt = [R + L @ L.T for L, R in zip(Ls, Rv)]
        x, P, M = zs[0], Rt[0], Ls[0]
        xk, Pk = zs[0], Rt[0]
        for z, R, L in zip(zs[1:], Rt[1:], Ls[1:]):
            x, P, M = up.update_consider(x, P, M, z, R, L)
            xk, Pk = KalmanUpdater(FIX).update(xk, Pk, z, R)
        e, ek = x - x_true, xk - x_true
        nees_c.append(e @ np.linalg.solve(P, e))
        nees_k.append(ek @ np.linalg.solve(Pk, ek))
    # mean of 1500 chi-square(3): sd 0.063, so +-0.2 is over 3 sigma
    assert abs(np.mean(nees_c) - 3.0) < 0.2, np.mean(nees_c)
    assert np.mean(nees_k) > 6.0, np.mean(nees_k)


def test_batch_rows_equal_single_updates():
    rng = np.random.default_rng(3)
    up = ConsiderKalmanUpdater(FIX)
    N, q = 5, 7
    X, Z = rng.normal(size=(N, 3)), rng.normal(size=(N, 3))
    P = np.stack([_spd(rng) for _ in range(N)])
    R = np.stack([_spd(rng, scale=0.2) for _ in range(N)])
    M, L = rng.normal(scale=0.3, size=(N, 3, q)), rng.normal(scale=0.3, size=(N, 3, q))
    xb, Pb, Mb = up.update_consider_batch(X, P, M, Z, R, L)
    for i in range(N):
        xi, Pi, Mi = up.update_consider(X[i], P[i], M[i], Z[i], R[i], L[i])
        np.testing.assert_array_equal(xb[i], xi)
        np.testing.assert_array_equal(Pb[i], Pi)
        np.testing.assert_array_equal(Mb[i], Mi)
