"""Same-scan clustering: greedy seed semantics, the chi-square rate, and the fused measurement."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from autonomy.estimation.clustering import cluster_consistent, fuse_cluster


def _maha2(a, b, Ra, Rb):
    d = a - b
    return float(d @ np.linalg.inv(Ra + Rb) @ d)


def test_clusters_partition_and_respect_their_seeds():
    rng = np.random.default_rng(0)
    for _ in range(30):
        m = int(rng.integers(1, 9))
        Z = rng.uniform(0.0, 2.0, (m, 3))
        R = np.stack([np.diag(rng.uniform(0.01, 0.1, 3)) for _ in range(m)])
        order = list(rng.permutation(m))
        clusters = cluster_consistent(Z, R, 9.0, order)
        assert sorted(i for c in clusters for i in c) == list(range(m))
        seeds = [c[0] for c in clusters]
        for c in clusters:
            assert all(_maha2(Z[i], Z[c[0]], R[i], R[c[0]]) <= 9.0 for i in c)
        for n, s in enumerate(seeds):  # a seed failed the gate of every earlier seed
            assert all(_maha2(Z[s], Z[t], R[s], R[t]) > 9.0 for t in seeds[:n])
    with pytest.raises(ValueError):
        cluster_consistent(np.zeros((2, 3)), np.stack([np.eye(3)] * 2), 9.0, [0, 0])


def test_two_detections_of_one_point_cluster_at_the_chi_square_rate():
    rng = np.random.default_rng(1)
    R = np.diag([0.05**2, 0.05**2, 0.02**2])
    gate = 7.81  # chi-square 95 %, 3 dof
    n = 4000
    together = 0
    for _ in range(n):
        Z = rng.multivariate_normal(np.zeros(3), R, size=2)
        together += len(cluster_consistent(Z, np.stack([R, R]), gate)) == 1
    rate = chi2.cdf(gate, 3)
    assert abs(together / n - rate) < 4 * np.sqrt(rate * (1 - rate) / n)


def test_fused_cluster_is_the_information_weighted_mean_with_the_mean_covariance():
    Z = np.array([[0.0, 0.0, 4.0], [0.3, -0.1, 4.1]])
    R = np.stack([np.diag([0.01, 0.04, 0.01]), np.diag([0.04, 0.01, 0.01])])
    mean, cov = fuse_cluster(Z, R)
    # per axis (diagonal R): mean = (z1/r1 + z2/r2) / (1/r1 + 1/r2)
    np.testing.assert_allclose(mean, [0.3 * 25 / 125, -0.1 * 100 / 125, 4.05])
    np.testing.assert_allclose(cov, np.diag([0.025, 0.025, 0.01]))
    one_mean, one_cov = fuse_cluster(Z[:1], R[:1])
    np.testing.assert_array_equal(one_mean, Z[0])
    np.testing.assert_array_equal(one_cov, R[0])
