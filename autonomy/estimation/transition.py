"""Transition models: how a state evolves over a time step (the transition-model role).

Each model gives the transition matrix ``F(dt)``, the process-noise covariance ``Q(dt)``, the
state function ``f(x, dt) = F x`` and :meth:`propagate_covar`, ``F P F^T + Q`` over any
leading batch axes. Times in seconds; ``dt_s`` must be >= 0.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def _check_dt(dt_s: ArrayLike) -> FloatArray:
    dt = np.asarray(dt_s, dtype=float)
    if not np.all(dt >= 0.0):
        raise ValueError(f"transition time step must be finite and >= 0 s, got {dt_s!r}")
    return dt


class ConstantPosition:
    """Static object with a random-walk position: ``x_k+1 = x_k + v_k``, ``v_k ~ N(0, q dt I)``.

    Paper 000 eqs. 17-19 (F = I for objects lying on the seabed). ``q`` is the position
    random-walk intensity in m^2/s; the state is ``ndim`` positions (m).

    Raises:
        ValueError: ``q`` negative or ``ndim`` < 1.
    """

    def __init__(self, process_noise_m2_per_s: float, ndim: int = 3) -> None:
        if not process_noise_m2_per_s >= 0.0 or ndim < 1:
            raise ValueError(
                f"ConstantPosition needs q >= 0 and ndim >= 1, got {process_noise_m2_per_s}, {ndim}"
            )
        self.process_noise_m2_per_s = float(process_noise_m2_per_s)
        self.ndim_state = int(ndim)
        self._eye = np.eye(self.ndim_state)

    def matrix(self, dt_s: float) -> FloatArray:
        """Transition matrix F (ndim, ndim): the identity."""
        _check_dt(dt_s)
        return self._eye.copy()

    def covar(self, dt_s: float) -> FloatArray:
        """Process noise Q (ndim, ndim) = q dt I, m^2."""
        return (self.process_noise_m2_per_s * float(_check_dt(dt_s))) * self._eye

    def function(self, state: ArrayLike, dt_s: float) -> FloatArray:
        """f(x, dt) = x, shape (..., ndim)."""
        _check_dt(dt_s)
        return np.array(state, dtype=float)

    def propagate_covar(self, covar: ArrayLike, dt_s: ArrayLike) -> FloatArray:
        """``F P F^T + Q = P + q dt I`` for ``covar`` (..., ndim, ndim) and ``dt_s`` () or (...)."""
        dt = _check_dt(dt_s)
        return np.asarray(covar, dtype=float) + (self.process_noise_m2_per_s * dt)[..., None, None] * self._eye


class ConstantVelocity:
    """Nearly constant velocity: white-noise acceleration of spectral density ``q`` per axis.

    State ``[position (ndim), velocity (ndim)]`` in m and m/s.
    ``F = [[I, dt I], [0, I]]``, ``Q = q [[dt^3/3 I, dt^2/2 I], [dt^2/2 I, dt I]]``
    (Bar-Shalom, Li and Kirubarajan 2001, section 6.2.2, the continuous white-noise
    acceleration model; Stone Soup's ``ConstantVelocity`` with axes grouped).

    Raises:
        ValueError: ``q`` negative or ``ndim`` < 1.
    """

    def __init__(self, accel_noise_m2_per_s3: float, ndim: int = 3) -> None:
        if not accel_noise_m2_per_s3 >= 0.0 or ndim < 1:
            raise ValueError(
                f"ConstantVelocity needs q >= 0 and ndim >= 1, got {accel_noise_m2_per_s3}, {ndim}"
            )
        self.accel_noise_m2_per_s3 = float(accel_noise_m2_per_s3)
        self.ndim = int(ndim)
        self.ndim_state = 2 * self.ndim

    def matrix(self, dt_s: float) -> FloatArray:
        """Transition matrix F (2 ndim, 2 ndim)."""
        dt = float(_check_dt(dt_s))
        F = np.eye(self.ndim_state)
        F[: self.ndim, self.ndim :] = dt * np.eye(self.ndim)
        return F

    def covar(self, dt_s: float) -> FloatArray:
        """Process noise Q (2 ndim, 2 ndim): m^2, m^2/s, m^2/s^2 blocks."""
        dt = float(_check_dt(dt_s))
        block = self.accel_noise_m2_per_s3 * np.array([[dt**3 / 3.0, dt**2 / 2.0], [dt**2 / 2.0, dt]])
        return np.kron(block, np.eye(self.ndim))

    def function(self, state: ArrayLike, dt_s: float) -> FloatArray:
        """f(x, dt) = F x for ``state`` (..., 2 ndim)."""
        return np.asarray(state, dtype=float) @ self.matrix(dt_s).T

    def propagate_covar(self, covar: ArrayLike, dt_s: float) -> FloatArray:
        """``F P F^T + Q`` for ``covar`` (..., 2 ndim, 2 ndim) and a scalar ``dt_s``."""
        F = self.matrix(dt_s)
        return F @ np.asarray(covar, dtype=float) @ F.T + self.covar(dt_s)
