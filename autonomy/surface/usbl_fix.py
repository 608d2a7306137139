"""The surface vehicle's USBL fix of the AUV in the mission NED frame, with its covariance.

The buoy's USBL head (paper 000 section VII: the buoy's USBL modem, docs/references.md
[P000]) measures range ``r``, bearing ``b`` and elevation ``e`` of the AUV's transponder in
the head frame. The buoy is a level 3-DOF vessel, so its attitude is its compass heading
``psi`` alone, and the fix is

    p_auv = p_buoy + R_z(psi) (m + R_bs d(r, b, e)),   d = r [cos e cos b, cos e sin b, sin e],

``p_buoy`` the buoy's GNSS position at the measurement time, ``m`` and ``R_bs`` the head's
mount offset and orientation. First-order covariance: the USBL noise through
``dp/d(r, b, e)``, the heading noise through ``dp/d psi`` and the buoy's own position
covariance (independent terms added).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.measurement import RangeBearingElevation
from autonomy.frames import rot_from_euler, rot_z

FloatArray = NDArray[np.float64]


def usbl_fix_ned(
    rbe: ArrayLike,
    buoy_pos_ned: ArrayLike,
    buoy_pos_cov_ne_m2: ArrayLike,
    heading_rad: float,
    *,
    mount_pos_body_m: ArrayLike,
    mount_rpy_rad: ArrayLike = (0.0, 0.0, 0.0),
    range_sigma_m: float,
    angle_sigma_rad: float,
    heading_sigma_rad: float,
) -> tuple[FloatArray, FloatArray]:
    """The transponder's NED position and covariance from one USBL fix on a level vessel.

    Args:
        rbe: (3,) measured range (m), bearing (rad, starboard > 0), elevation (rad, down > 0)
            in the head frame.
        buoy_pos_ned: (3,) the vessel's body-origin position at the fix, NED m.
        buoy_pos_cov_ne_m2: (2, 2) covariance of its north/east, m^2.
        heading_rad: compass heading at the fix, rad.
        mount_pos_body_m: (3,) head offset from the body origin, FRD m.
        mount_rpy_rad: (3,) head frame w.r.t. the body, rad.
        range_sigma_m: range noise (1 sigma) at this range, m.
        angle_sigma_rad: bearing and elevation noise (1 sigma) at this range, rad.
        heading_sigma_rad: compass heading noise (1 sigma), rad.

    Returns:
        ``(pos_ned (3,), cov_ned (3, 3))``, m and m^2.

    Raises:
        ValueError: a non-finite or non-positive range.
    """
    z = np.asarray(rbe, dtype=float).reshape(3)
    if not (math.isfinite(z[0]) and z[0] > 0.0):
        raise ValueError(f"usbl_fix_ned: range must be finite and > 0, got {z[0]}")
    head = RangeBearingElevation()
    R_bs = rot_from_euler(*np.asarray(mount_rpy_rad, dtype=float).reshape(3))
    R_nb = rot_z(float(heading_rad))
    lever_body = np.asarray(mount_pos_body_m, dtype=float).reshape(3) + R_bs @ head.inverse(z)
    pos = np.asarray(buoy_pos_ned, dtype=float).reshape(3) + R_nb @ lever_body
    J_rbe = R_nb @ R_bs @ head.inverse_jacobian(z)
    cov = J_rbe @ np.diag([range_sigma_m**2, angle_sigma_rad**2, angle_sigma_rad**2]) @ J_rbe.T
    dR_dpsi = np.array([[-math.sin(heading_rad), -math.cos(heading_rad), 0.0],
                        [math.cos(heading_rad), -math.sin(heading_rad), 0.0], [0.0, 0.0, 0.0]])
    j_psi = dR_dpsi @ lever_body
    cov += np.outer(j_psi, j_psi) * heading_sigma_rad**2
    cov[:2, :2] += np.asarray(buoy_pos_cov_ne_m2, dtype=float).reshape(2, 2)
    return pos, 0.5 * (cov + cov.T)


class UsblFixer:
    """The surface vehicle's onboard USBL processing: each valid USBL message of the AUV's
    transponder becomes a fix of the AUV in the mission frame (:func:`usbl_fix_ned`), with
    the vessel's GNSS-filter position taken back to the measurement time along its velocity.

    Args:
        mount_pos_body_m, mount_rpy_rad: the head's mount (FRD m, rad).
        range_sigma_m, range_sigma_frac: range noise ``range_sigma_m + range_sigma_frac * r``, m.
        angle_sigma_rad, angle_sigma_rad_per_m: angle noise ``angle_sigma_rad + angle_sigma_rad_per_m * r``.
        heading_sigma_rad: compass heading noise, rad.
    """

    def __init__(self, mount_pos_body_m: ArrayLike, mount_rpy_rad: ArrayLike, *, range_sigma_m: float,
                 range_sigma_frac: float, angle_sigma_rad: float, angle_sigma_rad_per_m: float,
                 heading_sigma_rad: float) -> None:
        self.mount_pos_body_m = np.asarray(mount_pos_body_m, dtype=float).reshape(3)
        self.mount_rpy_rad = np.asarray(mount_rpy_rad, dtype=float).reshape(3)
        self.range_sigma_m, self.range_sigma_frac = float(range_sigma_m), float(range_sigma_frac)
        self.angle_sigma_rad, self.angle_sigma_rad_per_m = float(angle_sigma_rad), float(angle_sigma_rad_per_m)
        self.heading_sigma_rad = float(heading_sigma_rad)

    def fix(self, rbe: ArrayLike, t_meas_s: float, t_nav_s: float, pos_ne_m: ArrayLike, vel_ne_mps: ArrayLike,
            pos_cov_ne_m2: ArrayLike, heading_rad: float) -> tuple[FloatArray, FloatArray]:
        """``(pos_ned (3,), cov_ned (3, 3))`` of the AUV from a USBL fix ``rbe`` measured at
        ``t_meas_s``, the vessel's filter position and velocity (2,) at ``t_nav_s`` and its
        covariance (2, 2), and its heading (rad). Raises ``ValueError`` on a bad range."""
        r = float(np.asarray(rbe, dtype=float).reshape(3)[0])
        back = np.asarray(pos_ne_m, dtype=float) - np.asarray(vel_ne_mps, dtype=float) * (t_nav_s - t_meas_s)
        return usbl_fix_ned(rbe, [back[0], back[1], 0.0], pos_cov_ne_m2, heading_rad,
                            mount_pos_body_m=self.mount_pos_body_m, mount_rpy_rad=self.mount_rpy_rad,
                            range_sigma_m=self.range_sigma_m + self.range_sigma_frac * r,
                            angle_sigma_rad=self.angle_sigma_rad + self.angle_sigma_rad_per_m * r,
                            heading_sigma_rad=self.heading_sigma_rad)
