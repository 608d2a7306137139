"""Target kinematics of paper 004 eq. (6) as an EKF transition model.

State (7,): ``[n, e, d]`` NED position (m), course ``psi`` (rad), course rate ``r``
(rad/s), surge ``u`` (m/s), heave ``w`` (m/s). Continuous model ``n' = u cos psi``,
``e' = u sin psi``, ``d' = w``, ``psi' = r``, and ``r, u, w`` driven by white noise (paper
004 eq. 6, docs/references.md [P004]); discretised with Euler steps of at most
``max_step_s``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
N_STATES = 7
POS, COURSE, COURSE_RATE, SURGE, HEAVE = slice(0, 3), 3, 4, 5, 6


class TargetKinematics:
    """Transition of the 7-state target model.

    Args:
        pos_noise_m2_per_s: position random-walk intensity (unmodelled sway), m^2/s.
        course_rate_noise: white-noise intensity on the course rate, rad^2/s^3.
        surge_noise: on the surge speed, m^2/s^3.
        heave_noise: on the heave speed, m^2/s^3.
        max_step_s: longest Euler step, s.

    Raises:
        ValueError: a negative intensity or a non-positive step.
    """

    ndim_state = N_STATES

    def __init__(self, pos_noise_m2_per_s: float, course_rate_noise: float, surge_noise: float, heave_noise: float,
                 max_step_s: float = 0.1) -> None:
        q = np.array([pos_noise_m2_per_s] * 3 + [0.0, course_rate_noise, surge_noise, heave_noise], dtype=float)
        if np.any(q < 0.0) or not max_step_s > 0.0:
            raise ValueError("TargetKinematics: noise intensities must be >= 0 and max_step_s > 0")
        self._q = q
        self.max_step_s = float(max_step_s)

    def _step(self, x: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
        c, s = math.cos(x[COURSE]), math.sin(x[COURSE])
        u = x[SURGE]
        x1 = x.copy()
        x1[0] += u * c * dt
        x1[1] += u * s * dt
        x1[2] += x[HEAVE] * dt
        x1[COURSE] += x[COURSE_RATE] * dt
        F = np.eye(N_STATES)
        F[0, COURSE], F[0, SURGE] = -u * s * dt, c * dt
        F[1, COURSE], F[1, SURGE] = u * c * dt, s * dt
        F[2, HEAVE] = dt
        F[COURSE, COURSE_RATE] = dt
        return x1, F

    def predict(self, x: ArrayLike, P: ArrayLike, dt_s: float) -> tuple[FloatArray, FloatArray]:
        """Mean (7,) and covariance (7, 7) ``dt_s`` >= 0 s later.

        Raises:
            ValueError: a negative or non-finite ``dt_s``.
        """
        if not (dt_s >= 0.0 and math.isfinite(dt_s)):
            raise ValueError(f"TargetKinematics.predict: dt_s must be finite and >= 0, got {dt_s}")
        x = np.array(x, dtype=float)
        P = np.array(P, dtype=float)
        n = max(int(math.ceil(dt_s / self.max_step_s - 1e-12)), 1) if dt_s > 0.0 else 0
        for _ in range(n):
            h = dt_s / n
            x, F = self._step(x, h)
            P = F @ P @ F.T + np.diag(self._q * h)
        return x, 0.5 * (P + P.T)

    def function(self, x: ArrayLike, dt_s: float) -> FloatArray:
        """Predicted mean only (7,)."""
        return self.predict(x, np.zeros((N_STATES, N_STATES)), dt_s)[0]
