"""Same-scan measurement clustering: detections of one scan consistent with a single point.

An imaging sonar's detector can put two boxes on one object in one frame. Under a point
measurement model (at most one detection per object per scan) the second box must be
clutter or a second object, and repeated duplicates make a phantom second object the more
probable world. Grouping the scan's detections that are mutually consistent with one point
(``(z_i - z_j)^T (R_i + R_j)^-1 (z_i - z_j) <= gate``, a chi-square test on their difference)
turns them into one cluster measurement of that object, the simplest extended-object
(cluster) measurement model (Gilholm and Salmond 2005 model an object's detections as a
cluster around it).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def cluster_consistent(
    z: ArrayLike, noise_covar: ArrayLike, gate_mahalanobis2: float, order: Sequence[int] | None = None
) -> list[list[int]]:
    """Greedy grouping of measurements consistent with one point.

    Measurements are visited in ``order`` (default: index order); each joins the first
    cluster whose first member (its seed) it passes the gate with, else seeds a new
    cluster. Seeds are never chained through intermediate members, so a cluster spans at
    most twice the gate.

    Args:
        z: (m, d) measurements.
        noise_covar: (m, d, d) their covariances.
        gate_mahalanobis2: squared Mahalanobis gate on a pair's difference (> 0).
        order: visiting order (a permutation of range(m)).

    Returns:
        Clusters as lists of measurement indices, in visiting order; each index once.

    Raises:
        ValueError: a gate that is not positive or an order that is not a permutation.
    """
    Z = np.asarray(z, dtype=float)
    R = np.asarray(noise_covar, dtype=float)
    m = len(Z)
    if not gate_mahalanobis2 > 0.0:
        raise ValueError(f"cluster gate must be > 0, got {gate_mahalanobis2}")
    idx = list(range(m)) if order is None else [int(i) for i in order]
    if sorted(idx) != list(range(m)):
        raise ValueError("order must be a permutation of the measurement indices")
    clusters: list[list[int]] = []
    for i in idx:
        for members in clusters:
            s = members[0]
            d = Z[i] - Z[s]
            if float(d @ np.linalg.solve(R[i] + R[s], d)) <= gate_mahalanobis2:
                members.append(i)
                break
        else:
            clusters.append([i])
    return clusters


def fuse_cluster(z: ArrayLike, noise_covar: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """One measurement (d,) and covariance (d, d) from a cluster's members (k, d), (k, d, d).

    The mean is the information-weighted mean. Duplicate detections of one object share
    most of their error (the platform's navigation error, where on the object the boxes
    land), so the covariance is the members' mean covariance (their errors fully
    correlated) rather than the smaller independent-fusion one.
    """
    Z = np.asarray(z, dtype=float)
    R = np.asarray(noise_covar, dtype=float)
    if len(Z) == 1:
        return Z[0].copy(), R[0].copy()
    info = np.linalg.inv(R)
    mean = np.linalg.solve(info.sum(axis=0), np.einsum("kij,kj->i", info, Z))
    return mean, R.mean(axis=0)
