"""Track-to-track test and fusion against Monte Carlo draws of correlated track errors."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from autonomy.estimation.track_fusion import cross_covariance, fuse_tracks, track_distance2


def _tracks(rng, n):
    """Two 3-D track errors sharing q = 2 common parameters: e_i = a_i + C_i theta."""
    A1 = np.diag([0.04, 0.09, 0.01])
    A2 = np.array([[0.06, 0.02, 0.0], [0.02, 0.05, 0.0], [0.0, 0.0, 0.02]])
    C1 = np.array([[0.20, 0.05], [0.0, 0.15], [0.0, 0.0]])
    C2 = np.array([[0.18, 0.0], [0.03, 0.16], [0.0, 0.02]])
    theta = rng.standard_normal((n, 2))
    e1 = rng.multivariate_normal(np.zeros(3), A1, n) + theta @ C1.T
    e2 = rng.multivariate_normal(np.zeros(3), A2, n) + theta @ C2.T
    return e1, e2, A1 + C1 @ C1.T, A2 + C2 @ C2.T, cross_covariance(C1, C2, 3)


def test_fused_covariance_is_the_fused_errors_covariance_and_smaller_than_either():
    rng = np.random.default_rng(3)
    e1, e2, P1, P2, P12 = _tracks(rng, 200_000)
    truth = np.array([1.0, -2.0, 4.0])
    x, P = fuse_tracks(truth + e1[0], P1, truth + e2[0], P2, P12)
    # the fusion is linear: x - truth = e1 + K (e2 - e1) with K = (P1 - P12) S^-1
    K = (P1 - P12) @ np.linalg.inv(P1 + P2 - P12 - P12.T)
    assert np.allclose(x - truth, e1[0] + K @ (e2[0] - e1[0]))
    fused = e1 + (e2 - e1) @ K.T
    emp = np.cov(fused.T)
    assert np.allclose(emp, P, atol=4e-3 * np.trace(P))
    # never worse than the better track, and the independent-error formula would claim less than
    # the truth (the shared part cannot average out)
    for Pi in (P1, P2):
        assert np.all(np.linalg.eigvalsh(Pi - P) > -1e-12)
    P_naive = np.linalg.inv(np.linalg.inv(P1) + np.linalg.inv(P2))
    assert np.trace(P_naive) < np.trace(emp) - 0.01


def test_independent_errors_give_the_information_weighted_mean():
    x1, x2 = np.array([0.0, 0.0]), np.array([1.0, 2.0])
    P1, P2 = np.diag([1.0, 4.0]), np.diag([3.0, 4.0])
    x, P = fuse_tracks(x1, P1, x2, P2)
    assert np.allclose(x, [0.25, 1.0])
    assert np.allclose(P, np.diag([0.75, 2.0]))


def test_distance_of_one_objects_tracks_is_chi_square_with_the_state_dimension():
    rng = np.random.default_rng(4)
    e1, e2, P1, P2, P12 = _tracks(rng, 20_000)
    S = P1 + P2 - P12 - P12.T
    d2 = np.einsum("ni,ij,nj->n", e1 - e2, np.linalg.inv(S), e1 - e2)
    assert track_distance2(e1[0], P1, e2[0], P2, P12) == pytest.approx(d2[0])
    # 99 % of pairs pass the 3-dof 99 % gate the world model uses; ignoring the shared part
    # (P12 = 0) inflates S and would let farther pairs pass
    assert np.mean(d2 <= stats.chi2.ppf(0.99, 3)) == pytest.approx(0.99, abs=0.004)
    assert stats.kstest(d2, stats.chi2(3).cdf).pvalue > 1e-3
    d2_indep = np.einsum("ni,ij,nj->n", e1 - e2, np.linalg.inv(P1 + P2), e1 - e2)
    assert np.mean(d2_indep) < 0.8 * np.mean(d2)


def test_singular_difference_covariance_is_infinitely_far():
    P = np.eye(2)
    assert track_distance2([0, 0], P, [1, 0], P, P) == float("inf")
    assert cross_covariance(None, np.ones((2, 1)), 2).shape == (2, 2)
