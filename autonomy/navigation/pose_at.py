"""The navigation estimate's pose moved to a measurement's own time.

The navigation filter's time is that of its last message (the last IMU message, 0-20 ms
before a sonar ping at 50 Hz); a consumer that places a measurement with the estimate
(a side-scan row, a scanning-sonar echo or fix, a forward-looking sonar detection) moves the
estimate to the measurement time first,
with the estimate's own velocity and body rates held over the gap (first order in the gap:
the gap is one IMU period at most; the error is the acceleration times the gap squared).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from autonomy.frames import euler_rate_matrix, rot_from_euler, wrap_angle
from autonomy.messages import NavEstimate

FloatArray = NDArray[np.float64]


def pose_at(nav: NavEstimate, t_s: float) -> tuple[FloatArray, FloatArray]:
    """The body-origin pose at ``t_s`` from the estimate ``nav`` (made at ``nav.t_s``).

    ``pos = pos_nav + R_nb(rpy_nav) v_body (t - t_nav)`` (NED, m) and
    ``rpy = rpy_nav + T(rpy_nav) omega_body (t - t_nav)`` (rad, yaw wrapped to [-pi, pi);
    ``T`` the Euler-rate matrix, [Fossen2021] eq. 2.41). ``t_s`` may be before ``nav.t_s``.

    Returns:
        pos_ned (3,) m and rpy_rad (3,) rad.
    """
    dt = float(t_s) - float(nav.t_s)
    rpy = np.asarray(nav.rpy_rad, dtype=float)
    pos = np.asarray(nav.pos_ned, dtype=float)
    if dt == 0.0:
        return pos.copy(), rpy.copy()
    pos = pos + rot_from_euler(*rpy) @ np.asarray(nav.vel_body_mps, dtype=float) * dt
    rpy = rpy + euler_rate_matrix(rpy[0], rpy[1]) @ np.asarray(nav.rate_body_radps, dtype=float) * dt
    rpy[2] = wrap_angle(float(rpy[2]))
    return pos, rpy


def estimate_at(nav: NavEstimate, t_s: float) -> NavEstimate:
    """``nav`` moved to ``t_s`` (:func:`pose_at`): stamped ``t_s``, its pose moved, its
    velocities, covariances and altitude kept (they change by a gap's motion, which the
    pose alone matters for here). ``nav`` itself when already at ``t_s``."""
    if float(t_s) == float(nav.t_s):
        return nav
    pos, rpy = pose_at(nav, t_s)
    return replace(nav, t_s=float(t_s), pos_ned=pos, rpy_rad=rpy)
