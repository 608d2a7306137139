"""Nearly-constant-turn (NCT) motion of the vehicle state particles (pure numpy).

State ``s = [north m, east m, v_north m/s, v_east m/s, turn rate rad/s]`` (NED horizontal;
heading ``atan2(v_east, v_north)``), paper 003 eq. 27 with the NCT model of Li and Jilkov
(Survey of maneuvering target tracking, part I, eqs. 6-7): over ``dt`` the velocity turns by
``omega dt``; the process noise is a linear acceleration along the heading and an angular
acceleration, ``diag(sigma_lin^2, sigma_ang^2)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def heading_rad(states: FloatArray) -> FloatArray:
    """(N,) heading (NED yaw) of states (N, 5)."""
    return np.arctan2(states[:, 3], states[:, 2])


def nct_predict(states: FloatArray, dt_s: float, sigma_lin_mps2: float, sigma_ang_radps2: float,
                rng: np.random.Generator) -> FloatArray:
    """Propagate states (N, 5) by ``dt_s`` with NCT motion and its process noise; returns (N, 5)."""
    n, e, vn, ve, w = states.T
    wt = w * dt_s
    small = np.abs(wt) < 1e-6
    safe_w = np.where(small, 1.0, w)
    s_w = np.where(small, dt_s, np.sin(wt) / safe_w)
    c_w = np.where(small, 0.5 * w * dt_s ** 2, (1.0 - np.cos(wt)) / safe_w)
    c, s = np.cos(wt), np.sin(wt)
    out = np.empty_like(states)
    out[:, 0] = n + s_w * vn - c_w * ve
    out[:, 1] = e + c_w * vn + s_w * ve
    out[:, 2] = c * vn - s * ve
    out[:, 3] = s * vn + c * ve
    out[:, 4] = w
    if sigma_lin_mps2 > 0.0 or sigma_ang_radps2 > 0.0:
        u = rng.standard_normal((len(states), 2)) * np.array([sigma_lin_mps2, sigma_ang_radps2])
        psi = heading_rad(out)
        cp, sp = np.cos(psi), np.sin(psi)
        out[:, 0] += 0.5 * dt_s ** 2 * cp * u[:, 0]
        out[:, 1] += 0.5 * dt_s ** 2 * sp * u[:, 0]
        out[:, 2] += dt_s * cp * u[:, 0]
        out[:, 3] += dt_s * sp * u[:, 0]
        out[:, 4] += dt_s * u[:, 1]
    return out
