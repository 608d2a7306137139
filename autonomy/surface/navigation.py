"""Navigation of a surface vessel from GNSS fixes and a compass: a constant-velocity
Kalman filter on north/east (Bar-Shalom, Li and Kirubarajan 2001, *Estimation with
Applications to Tracking and Navigation*, sec. 6.3.2, the discretised continuous white-noise
acceleration model), heading and yaw rate taken from the compass/AHRS as measured.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np
from numpy.typing import NDArray

from autonomy.messages import GpsMsg
from autonomy.surface.config import SurfaceNavigationConfig

FloatArray = NDArray[np.float64]


class GnssVelocityFilter:
    """State ``x = [n, e, v_n, v_e]`` (m, m/s, NED) and its (4, 4) covariance.

    Per axis, over ``dt`` with white acceleration of spectral density ``q = sigma_a^2``:
    ``F = [[1, dt], [0, 1]]``, ``Q = q [[dt^3/3, dt^2/2], [dt^2/2, dt]]``; a fix updates the
    position with ``R = sigma_gnss^2 I2``. The first valid fix initialises the position
    (velocity 0, standard deviation ``max_speed``).
    """

    def __init__(self, cfg: SurfaceNavigationConfig, initial_speed_sigma_mps: float = 1.0) -> None:
        self.cfg = cfg
        self._v0 = float(initial_speed_sigma_mps)
        self.reset()

    def reset(self) -> None:
        self.x = np.zeros(4)
        self.P = np.eye(4)
        self.t_s: float | None = None
        self.last_fix_t_s = -math.inf

    @property
    def initialised(self) -> bool:
        return self.t_s is not None

    def valid(self, t_s: float) -> bool:
        """True once initialised and while the last fix is at most ``max_fix_gap_s`` old."""
        return self.initialised and t_s - self.last_fix_t_s <= self.cfg.max_fix_gap_s

    def predict(self, t_s: float) -> None:
        """Propagate to ``t_s`` (no-op before the first fix or backwards in time)."""
        if self.t_s is None or t_s <= self.t_s:
            return
        dt = t_s - self.t_s
        q = self.cfg.accel_noise_mps2 ** 2
        F = np.eye(4)
        F[0, 2] = F[1, 3] = dt
        Q1 = q * np.array([[dt ** 3 / 3.0, dt ** 2 / 2.0], [dt ** 2 / 2.0, dt]])
        Q = np.zeros((4, 4))
        Q[np.ix_((0, 2), (0, 2))] = Q1
        Q[np.ix_((1, 3), (1, 3))] = Q1
        self.x = F @ self.x
        self.P = F @ self.P @ F.T + Q
        self.t_s = t_s

    def update(self, fixes: Iterable[GpsMsg]) -> int:
        """Fuse the valid fixes in time order; returns how many were used."""
        used = 0
        r = self.cfg.gnss_noise_m ** 2
        for msg in sorted((m for m in fixes if m.valid), key=lambda m: m.t_s):
            z = np.asarray(msg.pos_ne_m, dtype=float)
            if self.t_s is None:
                self.x = np.array([z[0], z[1], 0.0, 0.0])
                self.P = np.diag([r, r, self._v0 ** 2, self._v0 ** 2])
                self.t_s = float(msg.t_s)
            else:
                self.predict(float(msg.t_s))
                S = self.P[:2, :2] + r * np.eye(2)
                K = self.P[:, :2] @ np.linalg.inv(S)
                self.x = self.x + K @ (z - self.x[:2])
                self.P = (np.eye(4) - K @ np.eye(2, 4)) @ self.P
                self.P = 0.5 * (self.P + self.P.T)
            self.last_fix_t_s = max(self.last_fix_t_s, float(msg.t_s))
            used += 1
        return used

    @property
    def pos_ne_m(self) -> FloatArray:
        return self.x[:2].copy()

    @property
    def vel_ne_mps(self) -> FloatArray:
        return self.x[2:].copy()
