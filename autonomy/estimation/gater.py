"""Mahalanobis gate (the gater role) and the Gaussian innovation likelihoods it is computed from.

For predicted measurements ``z_pred_i`` with covariance ``H P_i H^T`` and measurements
``z_j`` with noise ``R_j``, the innovation ``d_ij = z_j - z_pred_i`` has covariance
``S_ij = H P_i H^T + R_j``; its squared Mahalanobis distance ``d^T S^-1 d`` is chi-square with
``m`` degrees of freedom when ``z_j`` comes from object ``i`` (Bar-Shalom, Li and Kirubarajan
2001, section 2.6), so a gate ``d^T S^-1 d <= g`` keeps the true pair with probability
``F_chi2(g; m)``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import gammaincinv

FloatArray = NDArray[np.float64]
_LOG_2PI = math.log(2.0 * math.pi)


def innovation_log_likelihoods(
    z_pred: ArrayLike, covar_pred: ArrayLike, z: ArrayLike, noise_covar: ArrayLike,
    shared_covar: ArrayLike | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Squared Mahalanobis distances and Gaussian log-likelihoods of every (object, measurement) pair.

    Args:
        z_pred: (n, m) predicted measurements.
        covar_pred: (n, m, m) their covariances ``H P H^T``.
        z: (k, m) measurements.
        noise_covar: (k, m, m) their noise covariances.
        shared_covar: optional (n, k, m, m) part of ``covar_pred + noise_covar`` the object
            and the measurement share (errors common to both, ``H M L^T + L M^T H^T`` of
            :class:`autonomy.estimation.updater.ConsiderKalmanUpdater`), subtracted from
            each pair's innovation covariance.

    Returns:
        ``maha2`` (n, k) and ``log N(z_j; z_pred_i, S_ij)`` (n, k).

    Raises:
        numpy.linalg.LinAlgError: an innovation covariance is not positive definite.
    """
    z_pred = np.asarray(z_pred, dtype=float)
    z = np.asarray(z, dtype=float)
    S = np.asarray(covar_pred, dtype=float)[:, None] + np.asarray(noise_covar, dtype=float)[None]
    if shared_covar is not None:
        S = S - np.asarray(shared_covar, dtype=float)
    d = z[None] - z_pred[:, None]  # (n, k, m)
    L = np.linalg.cholesky(S)
    w = np.linalg.solve(L, d[..., None])[..., 0]
    maha2 = np.einsum("umk,umk->um", w, w)
    logdet = 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
    loglik = -0.5 * (maha2 + logdet + z.shape[-1] * _LOG_2PI)
    return maha2, loglik


def mahalanobis2(residual: ArrayLike, covar: ArrayLike) -> float:
    """Squared Mahalanobis distance ``r^T S^-1 r`` of one innovation ``residual`` (m,) with
    covariance ``covar`` (m, m) (Bar-Shalom, Li and Kirubarajan 2001, section 2.6).

    Raises:
        numpy.linalg.LinAlgError: a singular ``covar``.
    """
    r = np.asarray(residual, dtype=float)
    return float(r @ np.linalg.solve(np.asarray(covar, dtype=float), r))


class MahalanobisGater:
    """Admits pairs whose squared Mahalanobis distance is at most ``threshold``.

    Raises:
        ValueError: a threshold that is not positive.
    """

    def __init__(self, threshold: float) -> None:
        if not threshold > 0.0:
            raise ValueError(f"MahalanobisGater threshold must be > 0, got {threshold}")
        self.threshold = float(threshold)

    @classmethod
    def chi_square(cls, probability: float, dof: int) -> MahalanobisGater:
        """Gate keeping a true pair with ``probability`` for ``dof``-dimensional measurements.

        Raises:
            ValueError: probability outside (0, 1) or dof < 1.
        """
        if not 0.0 < probability < 1.0 or dof < 1:
            raise ValueError(f"chi-square gate needs 0 < probability < 1 and dof >= 1, got {probability}, {dof}")
        # the chi-square quantile as scipy.stats.chi2.ppf forms it (2 P^-1(m/2, p), same bits),
        # without importing scipy.stats (~25 MB and ~0.3 s on the vehicle)
        return cls(float(2 * gammaincinv(dof / 2, probability)))

    def rejects(self, maha2: ArrayLike) -> NDArray[np.bool_]:
        """Mask of the pairs outside the gate (same shape as ``maha2``)."""
        return np.asarray(maha2) > self.threshold

    def admits(self, residual: ArrayLike, covar: ArrayLike) -> bool:
        """Whether one innovation ``residual`` (m,) with covariance ``covar`` (m, m) lies inside
        the gate (:func:`mahalanobis2` at most the threshold)."""
        return mahalanobis2(residual, covar) <= self.threshold
