"""Navigation of a surface vessel from GNSS fixes, a compass and its own thrust: a linear
Kalman filter per horizontal axis on position, velocity over ground and a disturbance
acceleration (the current's drag and whatever the thrust model misses), the standard
dynamic-positioning observer structure with a bias state modelled as a random walk
([Fossen2021-3DOF]: Fossen 2021, *Handbook of Marine Craft Hydrodynamics and Motion
Control*, 2nd ed., ch. 13). Heading and yaw rate are taken from the compass/AHRS
as measured.

In NED, with ``R = R(psi)`` the heading rotation, ``M = diag(m_u, m_v)`` the surge and sway
masses (added mass included), ``tau`` the thrust in body axes
(:meth:`GnssDisturbanceFilter.set_input`) and ``K = R M^-1 diag(d_l + d_q |u|, d_l + d_q |v|) R^T``
the drag slope linearised at the present velocity::

    p' = v,   v' = R M^-1 tau - K v + b + w_a,   b' = w_b          (GNSS measures p)

discretised over ``dt`` (Euler in the transition, ``Q = diag(0, q_a dt, q_b dt)`` per axis).
The drag acts on the velocity over ground: the current's share is part of ``b``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.updater import kalman_update
from autonomy.messages import GpsMsg
from autonomy.surface.config import SurfaceNavigationConfig

FloatArray = NDArray[np.float64]


class GnssDisturbanceFilter:
    """State ``x = [n, e, v_n, v_e, b_n, b_e]`` (m, m/s, m/s^2, NED) and its covariance.

    Args:
        cfg: noise settings.
        mass_kg: (2,) surge and sway mass + added mass, kg.
        drag_linear: (2,) surge and sway linear drag, N s/m.
        drag_quadratic: (2,) surge and sway quadratic drag, N s^2/m^2.
        initial_speed_sigma_mps: velocity standard deviation at the first fix.
    """

    def __init__(self, cfg: SurfaceNavigationConfig, mass_kg: ArrayLike, drag_linear: ArrayLike,
                 drag_quadratic: ArrayLike, initial_speed_sigma_mps: float = 1.0) -> None:
        self.cfg = cfg
        self._m = np.asarray(mass_kg, dtype=float).reshape(2)
        self._dl = np.asarray(drag_linear, dtype=float).reshape(2)
        self._dq = np.asarray(drag_quadratic, dtype=float).reshape(2)
        self._v0 = float(initial_speed_sigma_mps)
        self.reset()

    def reset(self) -> None:
        self.x = np.zeros(6)
        self.P = np.eye(6)
        self.t_s: float | None = None
        self.last_fix_t_s = -math.inf
        self._a_u = np.zeros(2)
        self._R = np.eye(2)

    @property
    def initialised(self) -> bool:
        return self.t_s is not None

    def valid(self, t_s: float) -> bool:
        """True once initialised and while the last fix is at most ``max_fix_gap_s`` old."""
        return self.initialised and t_s - self.last_fix_t_s <= self.cfg.max_fix_gap_s

    def set_input(self, force_body_n: ArrayLike, heading_rad: float) -> None:
        """The thrust (2,) in body axes (surge, sway), N, applied from now on at heading
        ``heading_rad``."""
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        self._R = np.array([[c, -s], [s, c]])
        self._a_u = self._R @ (np.asarray(force_body_n, dtype=float).reshape(2) / self._m)

    def predict(self, t_s: float) -> None:
        """Propagate to ``t_s`` (no-op before the first fix or backwards in time)."""
        if self.t_s is None or t_s <= self.t_s:
            return
        dt = t_s - self.t_s
        R = self._R
        v_body = R.T @ self.x[2:4]
        K = R @ np.diag((self._dl + self._dq * np.abs(v_body)) / self._m) @ R.T
        F = np.eye(6)
        F[0:2, 2:4] = dt * np.eye(2)
        F[2:4, 2:4] -= dt * K
        F[2:4, 4:6] = dt * np.eye(2)
        Q = np.diag([0.0, 0.0, *([self.cfg.accel_noise_mps2 ** 2 * dt] * 2),
                     *([self.cfg.disturbance_walk_mps2 ** 2 * dt] * 2)])
        self.x = F @ self.x
        self.x[2:4] += self._a_u * dt
        self.P = F @ self.P @ F.T + Q
        self.t_s = t_s

    def update(self, fixes: Iterable[GpsMsg]) -> int:
        """Fuse the valid fixes in time order; returns how many were used."""
        used = 0
        r = self.cfg.gnss_noise_m ** 2
        H = np.eye(2, 6)
        for msg in sorted((m for m in fixes if m.valid), key=lambda m: m.t_s):
            z = np.asarray(msg.pos_ne_m, dtype=float)
            if self.t_s is None:
                self.x = np.array([z[0], z[1], 0.0, 0.0, 0.0, 0.0])
                b0 = self.cfg.initial_disturbance_mps2 ** 2
                self.P = np.diag([r, r, self._v0 ** 2, self._v0 ** 2, b0, b0])
                self.t_s = float(msg.t_s)
            else:
                self.predict(float(msg.t_s))
                self.x, self.P = kalman_update(self.x, self.P, z - H @ self.x, H, r * np.eye(2))
            self.last_fix_t_s = max(self.last_fix_t_s, float(msg.t_s))
            used += 1
        return used

    @property
    def pos_ne_m(self) -> FloatArray:
        return self.x[:2].copy()

    @property
    def vel_ne_mps(self) -> FloatArray:
        return self.x[2:4].copy()

    @property
    def disturbance_ne_mps2(self) -> FloatArray:
        return self.x[4:].copy()
