"""Region of interest in the sonar image from the tracker's covariance (paper 004 section 4).

The target's NED position covariance is rotated into the sonar frame (eq. 12-13) and carried
to polar coordinates through the Jacobian of (range, azimuth) (eq. 14-15); the ROI is the
Cartesian product of ``range +- (k sigma_r + size / 2)`` and ``azimuth +- (k sigma_a +
atan(size / 2 / range))`` (eq. 16, with the size taken as half on each side). Its floor is
set by the measurement noise and its growth by the process noise (section 4.2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.measurement import RangeAzimuth

FloatArray = NDArray[np.float64]
_RA = RangeAzimuth()


@dataclass(frozen=True, slots=True)
class PolarRoi:
    """Polar window in the sonar frame: centre and half-widths (m, rad), and the polar
    covariance (2, 2) of the predicted position (m^2, m rad, rad^2)."""

    range_m: float
    azimuth_rad: float
    half_range_m: float
    half_azimuth_rad: float
    covar_polar: FloatArray

    def contains(self, range_m: ArrayLike, azimuth_rad: ArrayLike) -> NDArray[np.bool_]:
        """Which (range, azimuth) points lie inside."""
        dr = np.abs(np.asarray(range_m, dtype=float) - self.range_m)
        da = np.abs(np.angle(np.exp(1j * (np.asarray(azimuth_rad, dtype=float) - self.azimuth_rad))))
        return (dr <= self.half_range_m) & (da <= self.half_azimuth_rad)

    def centre_distance(self, range_m: ArrayLike, azimuth_rad: ArrayLike) -> FloatArray:
        """Normalised distance to the centre (0 at the centre, 1 on the ROI's corners' axes)."""
        dr = (np.asarray(range_m, dtype=float) - self.range_m) / self.half_range_m
        da = np.angle(np.exp(1j * (np.asarray(azimuth_rad, dtype=float) - self.azimuth_rad))) / self.half_azimuth_rad
        return np.hypot(dr, da) / math.sqrt(2.0)


    def outline(self, n_arc: int = 16) -> FloatArray:
        """Closed outline of the window, (2 n_arc + 1, 2) (range m, azimuth rad): the near arc
        from port to starboard, the far arc back, and the first point again (the ranges
        clipped at 0), for drawing it on a fan image."""
        a = self.azimuth_rad + np.linspace(-self.half_azimuth_rad, self.half_azimuth_rad, max(int(n_arc), 2))
        near = max(self.range_m - self.half_range_m, 0.0)
        far = self.range_m + self.half_range_m
        pts = np.concatenate([np.c_[np.full(a.size, near), a], np.c_[np.full(a.size, far), a[::-1]]])
        return np.vstack([pts, pts[:1]])


def polar_roi(target_ned: ArrayLike, covar_pos_ned: ArrayLike, head_ned: ArrayLike, R_ns: ArrayLike,
              k_sigma: float, size_m: float) -> PolarRoi:
    """ROI of a target estimate (3,) NED with position covariance (3, 3) m^2 seen from a sonar
    head at ``head_ned`` (3,) with sonar->NED rotation ``R_ns`` (3, 3).

    Raises:
        ValueError: the target is at the head (no polar coordinates).
    """
    R_sn = np.asarray(R_ns, dtype=float).T
    p_s = R_sn @ (np.asarray(target_ned, dtype=float) - np.asarray(head_ned, dtype=float))
    if np.hypot(p_s[0], p_s[1]) < 1e-6:
        raise ValueError("polar_roi: the target is on the sonar's vertical axis")
    r, a = _RA.function(p_s)
    J = _RA.jacobian(p_s) @ R_sn  # d(range, azimuth)/d(target NED)
    C = J @ np.asarray(covar_pos_ned, dtype=float) @ J.T
    half_r = k_sigma * math.sqrt(max(C[0, 0], 0.0)) + 0.5 * size_m
    half_a = k_sigma * math.sqrt(max(C[1, 1], 0.0)) + math.atan2(0.5 * size_m, r)
    return PolarRoi(float(r), float(a), float(half_r), float(min(half_a, math.pi)), C)
