"""Kalman updaters (the updater role): a Gaussian prior corrected by one measurement.

Both use the Joseph form ``P+ = (I - K H) P (I - K H)^T + K R K^T`` (Bucy and Joseph 1968),
which stays symmetric positive semi-definite for any gain, and return ``(mean, covar)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.measurement import PositionFix, RangeAzimuth, RangeBearingElevation

FloatArray = NDArray[np.float64]


class KalmanUpdater:
    """Kalman update for a linear :class:`PositionFix` (Kalman 1960).

    ``S = H P H^T + R``, ``K = P H^T S^-1``, ``x+ = x + K (z - H x)``. The gain is obtained
    with a linear solve (``S`` and ``P`` symmetric), never an explicit inverse.
    """

    def __init__(self, model: PositionFix) -> None:
        self.model = model

    def predict_measurement(self, mean: ArrayLike, covar: ArrayLike,
                            noise_covar: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """Predicted measurement (m,) and innovation covariance S (m, m)."""
        R = self.model.covar() if noise_covar is None else np.asarray(noise_covar, dtype=float)
        return self.model.function(mean), self.model.project_covar(covar) + R

    def update(self, mean: ArrayLike, covar: ArrayLike, z: ArrayLike,
               noise_covar: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """Posterior mean (n,) and covariance (n, n) given ``z`` (m,) with noise R (m, m)
        (default: the model's).

        Raises:
            numpy.linalg.LinAlgError: singular innovation covariance.
        """
        model = self.model
        x = np.asarray(mean, dtype=float)
        P = np.asarray(covar, dtype=float)
        R = model.covar() if noise_covar is None else np.asarray(noise_covar, dtype=float)
        S = model.project_covar(P) + R
        K = np.linalg.solve(S, model.cross_covar(P)).T  # P H^T S^-1 (P, S symmetric)
        x_new = x + K @ model.residual(z, model.function(x))
        I_KH = np.eye(model.ndim_state)
        I_KH[:, model.mapping] -= K
        P_new = I_KH @ P @ I_KH.T + K @ R @ K.T
        return x_new, 0.5 * (P_new + P_new.T)

    def update_batch(self, mean: ArrayLike, covar: ArrayLike, z: ArrayLike,
                     noise_covar: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """:meth:`update` of N independent pairs at once: means (N, n), covariances (N, n, n),
        measurements (N, m) and their noise (N, m, m) -> posterior means (N, n) and
        covariances (N, n, n).

        Each pair goes through the same floating-point operations as :meth:`update` (numpy's
        batched ``solve`` and ``matmul`` run the per-matrix kernels of the single calls), so
        row i equals ``update(mean[i], covar[i], z[i], noise_covar[i])`` bit for bit.

        Raises:
            numpy.linalg.LinAlgError: a singular innovation covariance (in any pair).
        """
        model = self.model
        x = np.asarray(mean, dtype=float)
        P = np.asarray(covar, dtype=float)
        R = np.asarray(noise_covar, dtype=float)
        S = model.project_covar(P) + R
        K = np.linalg.solve(S, model.cross_covar(P)).swapaxes(-1, -2)  # (N, n, m)
        r = model.residual(z, model.function(x))
        x_new = x + np.matmul(K, r[..., None])[..., 0]
        I_KH = np.broadcast_to(np.eye(model.ndim_state), P.shape).copy()
        I_KH[..., :, model.mapping] -= K
        P_new = I_KH @ P @ I_KH.swapaxes(-1, -2) + K @ R @ K.swapaxes(-1, -2)
        return x_new, 0.5 * (P_new + P_new.swapaxes(-1, -2))


class ConsiderKalmanUpdater(KalmanUpdater):
    """Schmidt-Kalman ("consider") update for a linear :class:`PositionFix` ([Schmidt1966]).

    Errors shared between the state and its measurements enter through unit-variance
    consider parameters ``u`` that are not estimated: the state's error is ``e_r + M u``
    (``covar`` = ``P_r + M M^T``, ``M`` (n, q) its consider sensitivity) and the
    measurement's ``L u + v`` (``noise_covar`` = ``R_v + L L^T``, ``L`` (m, q)). Then

        S = H P H^T + R - H M L^T - L M^T H^T,   G = P H^T - M L^T,   K = G S^-1,
        x+ = x + K (z - H x),   P+ = P - K G^T - G K^T + K S K^T,   M+ = M + K (L - H M),

    the minimum-variance update that never lets the shared part average out: repeated
    measurements with the same ``L`` leave ``M+ M+^T -> L L^T``. With ``M`` and ``L`` zero
    it is the Kalman update (to rounding).
    """

    def update_consider_batch(self, mean: ArrayLike, covar: ArrayLike, sens: ArrayLike, z: ArrayLike,
                              noise_covar: ArrayLike, noise_sens: ArrayLike
                              ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """N pairs at once: means (N, n), covariances (N, n, n), sensitivities ``M`` (N, n, q),
        measurements (N, m), noise covariances (N, m, m) and their sensitivities ``L``
        (N, m, q) -> posterior means (N, n), covariances (N, n, n) and sensitivities (N, n, q).

        Raises:
            numpy.linalg.LinAlgError: a singular innovation covariance (in any pair).
        """
        model = self.model
        x = np.asarray(mean, dtype=float)
        P = np.asarray(covar, dtype=float)
        M = np.asarray(sens, dtype=float)
        R = np.asarray(noise_covar, dtype=float)
        L = np.asarray(noise_sens, dtype=float)
        HM = M[..., model.mapping, :]
        G = model.cross_covar(P).swapaxes(-1, -2) - M @ L.swapaxes(-1, -2)  # P H^T - M L^T (N, n, m)
        C = HM @ L.swapaxes(-1, -2)
        S = model.project_covar(P) + R - C - C.swapaxes(-1, -2)
        S = 0.5 * (S + S.swapaxes(-1, -2))
        K = np.linalg.solve(S, G.swapaxes(-1, -2)).swapaxes(-1, -2)  # G S^-1 (S symmetric)
        r = model.residual(z, model.function(x))
        x_new = x + np.matmul(K, r[..., None])[..., 0]
        KGt = K @ G.swapaxes(-1, -2)
        P_new = P - KGt - KGt.swapaxes(-1, -2) + K @ S @ K.swapaxes(-1, -2)
        M_new = M + K @ (L - HM)
        return x_new, 0.5 * (P_new + P_new.swapaxes(-1, -2)), M_new

    def update_consider(self, mean: ArrayLike, covar: ArrayLike, sens: ArrayLike, z: ArrayLike,
                        noise_covar: ArrayLike, noise_sens: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """One pair of :meth:`update_consider_batch`: (n,), (n, n), (n, q) -> the same."""
        x, P, M = self.update_consider_batch(np.asarray(mean, float)[None], np.asarray(covar, float)[None],
                                             np.asarray(sens, float)[None], np.asarray(z, float)[None],
                                             np.asarray(noise_covar, float)[None],
                                             np.asarray(noise_sens, float)[None])
        return x[0], P[0], M[0]


class ExtendedKalmanUpdater:
    """Extended Kalman update for a nonlinear measurement model of the state (its ``function``
    and ``jacobian`` taking the state; angle residuals wrapped by the model's ``residual``).

    ``H = dh/dx (x)``, ``S = H P H^T + R``, ``K = P H^T S^-1``, ``x+ = x + K r(z, h(x))``.
    """

    def __init__(self, model: RangeBearingElevation | RangeAzimuth | PositionFix) -> None:
        self.model = model

    def update(self, mean: ArrayLike, covar: ArrayLike, z: ArrayLike,
               noise_covar: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Posterior mean (n,) and covariance (n, n) given ``z`` (m,) and its noise R (m, m).

        Raises:
            numpy.linalg.LinAlgError: singular innovation covariance.
        """
        x = np.asarray(mean, dtype=float)
        P = np.asarray(covar, dtype=float)
        R = np.asarray(noise_covar, dtype=float)
        H = self.model.jacobian(x)
        PHt = P @ H.T
        S = H @ PHt + R
        K = np.linalg.solve(S, PHt.T).T
        x_new = x + K @ self.model.residual(z, self.model.function(x))
        I_KH = np.eye(x.size) - K @ H
        P_new = I_KH @ P @ I_KH.T + K @ R @ K.T
        return x_new, 0.5 * (P_new + P_new.T)
