"""The filter's scalar-written prediction against the dense matrix form of the same model.

``NavigationFilter.predict`` forms its 3 x 3 blocks in Python floats; here every predict of a
filtered survey (IMU, DVL, depth and GPS messages, a seabed slope for the altitude filter)
is recomputed from the state before it with full numpy matrices: ``F = I + dt d(p_dot)/dx``
built from ``R = Rz Ry Rx`` and the finite-difference Jacobian of ``R(att) v``, ``Q`` from the
module docstring's noise terms, and ``P' = F P F^T + Q``.
"""

from __future__ import annotations

import numpy as np

from autonomy.frames import euler_rate_matrix, rot_from_euler
from autonomy.navigation import NavigationFilter
from autonomy.navigation.config import NavigationConfig
from autonomy.navigation.ekf import SEABED_RELIEF_M_PER_SQRT_M
from tests.support import NAV_MOUNTS, NAV_NOISE, SURVEY_TRUTHS, fly_filters
from sim.sensors.nav_suite import build_nav_sensors
from scenarios.schema import SensorsConfig


def _fd_jacobian(att: np.ndarray, v: np.ndarray, eps: float = 1e-7) -> np.ndarray:
    cols = [(rot_from_euler(*(att + eps * e)) @ v - rot_from_euler(*(att - eps * e)) @ v) / (2 * eps)
            for e in np.eye(3)]
    return np.column_stack(cols)


def _dense_predict(f: NavigationFilter, t_s: float):
    """(x, P, altitude, altitude variance) after predicting ``f`` to ``t_s``, in dense matrices."""
    dt = t_s - f._t_s
    x, P = f._x.copy(), f._P.copy()
    tau = f._t_s + 0.5 * dt - f._t_imu_s
    rpy = f._rpy_meas + (euler_rate_matrix(*f._rpy_meas[:2]) @ f._rate_meas * tau if tau > 0 else 0.0)
    att = rpy - x[3:6]
    R = rot_from_euler(*att)
    one_s = 1.0 + x[6]
    v_m = f._vel_dvl_meas - x[7:10]
    v_body = v_m / one_s - np.cross(f._omega_at_dvl, f._r_dvl)
    J = _fd_jacobian(att, v_body)
    F = np.eye(10)
    F[0:3, 3:6] = -J * dt
    F[0:3, 6] = -(R @ v_m) / one_s**2 * dt
    F[0:3, 7:10] = -R / one_s * dt
    Q = np.zeros((10, 10))
    Q[0:3, 0:3] = J @ np.diag(NAV_NOISE.attitude_noise_rad**2) @ J.T * dt**2
    Q[5, 5] = NAV_NOISE.heading_rw_rad_per_sqrt_s**2 * dt
    cfg = f.cfg
    age = min(f._t_s - f._t_dvl_valid_s, cfg.dvl_timeout_s)
    q_vel = cfg.hold_accel_sigma_mps2**2 * (2 * age * dt + dt * dt)
    if f._t_s - f._t_dvl_valid_s > cfg.dvl_timeout_s:
        q_vel += cfg.dvl_lost_noise_mps_per_sqrt_s**2 * dt
    Q[7:10, 7:10] = q_vel * np.eye(3)
    v_ned = R @ v_body
    alt, alt_var = f._altitude_m, f._altitude_var_m2
    if np.isfinite(alt):
        h = np.array([*f._seabed_grad_ne, -1.0])
        alt_var += (float(h @ R @ P[7:10, 7:10] @ R.T @ h) / one_s**2 * dt * dt
                    + SEABED_RELIEF_M_PER_SQRT_M**2 * np.hypot(*v_ned[:2]) * dt)
        alt += float(h @ v_ned) * dt
    x[0:3] += v_ned * dt
    return x, F @ P @ F.T + Q, alt, alt_var


class _Checked(NavigationFilter):
    """Compares every predict with the dense form."""

    worst = 0.0

    def predict(self, t_s: float) -> None:
        if float(t_s) <= self._t_s:
            return super().predict(t_s)
        x, P, alt, alt_var = _dense_predict(self, float(t_s))
        super().predict(t_s)
        np.testing.assert_allclose(self._x, x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(self._P, P, rtol=1e-6, atol=1e-16)
        if np.isfinite(alt):
            assert abs(self._altitude_m - alt) < 1e-9
            assert abs(self._altitude_var_m2 - alt_var) < 1e-9 * max(alt_var, 1.0)
        type(self).checked += 1

    checked = 0


def test_predict_matches_dense_matrix_form_over_a_survey():
    sensors = build_nav_sensors(SensorsConfig(), NAV_MOUNTS, 3)
    f = _Checked(NavigationConfig(), SURVEY_TRUTHS[0].pos_ned, float(SURVEY_TRUTHS[0].rpy_rad[2]), NAV_NOISE, mounts=NAV_MOUNTS)
    for _ in fly_filters([f], sensors, SURVEY_TRUTHS[:300]):
        pass
    assert _Checked.checked > 250
    assert np.isfinite(f._altitude_m)  # the altitude branch was exercised
