"""Kalman updaters (the updater role): a Gaussian prior corrected by one measurement.

Every update uses the Joseph form ``P+ = (I - K H) P (I - K H)^T + K R K^T`` (Bucy and Joseph
1968), which stays symmetric positive semi-definite for any gain, obtains the gain by a
linear solve (never an explicit inverse) and returns ``(mean, covar)``. :func:`kalman_update`
is the one update of a linearised measurement: the extended updater, the vehicle's
navigation filter (:mod:`autonomy.navigation.ekf`), the surface vessel's
(:mod:`autonomy.surface.navigation`) and the target tracker use it; :class:`KalmanUpdater`
is the same update for a measurement that selects state entries, batched for the world model.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.measurement import PositionFix, RangeAzimuth, RangeBearingElevation

FloatArray = NDArray[np.float64]


def kalman_update(mean: ArrayLike, covar: ArrayLike, residual: ArrayLike, H: ArrayLike,
                  noise_covar: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """The Kalman update of a prior ``mean`` (n,), ``covar`` (n, n) by an innovation
    ``residual`` (m,) (``z - h(x)``, angles wrapped by the caller) with measurement Jacobian
    ``H`` (m, n) and noise ``noise_covar`` (m, m) ([BarShalom2001] sections 5.2 and 10.3;
    extended when ``H`` is a linearisation):

        S = H P H^T + R,   K = P H^T S^-1 (a linear solve),   x+ = x + K r,
        P+ = (I - K H) P (I - K H)^T + K R K^T   (Joseph form, symmetrised).

    Returns the posterior mean (n,) and covariance (n, n).

    Raises:
        numpy.linalg.LinAlgError: a singular innovation covariance.
    """
    x = np.asarray(mean, dtype=float)
    P = np.asarray(covar, dtype=float)
    H = np.asarray(H, dtype=float)
    R = np.asarray(noise_covar, dtype=float)
    PHt = P @ H.T
    S = H @ PHt + R
    K = np.linalg.solve(S, PHt.T).T  # P H^T S^-1 (P, S symmetric)
    x_new = x + K @ np.asarray(residual, dtype=float)
    I_KH = np.eye(x.size) - K @ H
    P_new = I_KH @ P @ I_KH.T + K @ R @ K.T
    return x_new, 0.5 * (P_new + P_new.T)


class KalmanUpdater:
    """Kalman update for a linear :class:`PositionFix` (Kalman 1960), batched: the
    measurement selects state entries (``model.mapping``), so ``H P``, ``P H^T`` and
    ``I - K H`` are taken by indexing, for many (prior, measurement) pairs in one call (the
    world model's). The same update as :func:`kalman_update` with ``H`` the selection matrix
    (to rounding).

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
        R = self.model.covar() if noise_covar is None else np.asarray(noise_covar, dtype=float)
        x, P = self.update_batch(np.asarray(mean, dtype=float)[None], np.asarray(covar, dtype=float)[None],
                                 np.asarray(z, dtype=float)[None], R[None])
        return x[0], P[0]

    def update_batch(self, mean: ArrayLike, covar: ArrayLike, z: ArrayLike,
                     noise_covar: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """:meth:`update` of N independent pairs at once: means (N, n), covariances (N, n, n),
        measurements (N, m) and their noise (N, m, m) -> posterior means (N, n) and
        covariances (N, n, n).

        :meth:`update` is this with one pair, so a pair updated alone and in a batch give
        the same bits (numpy's batched ``solve`` and ``matmul`` run the per-matrix kernels
        whatever the batch size; the world model relies on it).

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
        return kalman_update(x, covar, self.model.residual(z, self.model.function(x)), self.model.jacobian(x),
                             noise_covar)
