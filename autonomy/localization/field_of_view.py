"""Sonar field-of-view predicate: was a NED point inside the FLS fan at a given pose?

The PMHA uses it as the visibility probability of an anchor at scan time.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_from_euler
from autonomy.localization.sonar_projection import sonar_to_body_rotation, sonar_to_spherical

FloatArray = NDArray[np.float64]


def fls_visibility(
    pos_ned: ArrayLike,
    rpy_rad: ArrayLike,
    mount_pos_body_m: ArrayLike,
    mount_rpy_rad: ArrayLike,
    *,
    range_min_m: float,
    range_max_m: float,
    fov_rad: float,
    vertical_fov_rad: float | None = None,
    margin_m: float = 0.0,
) -> Callable[[FloatArray], NDArray[np.bool_]]:
    """Predicate ``visible(points_ned (N, 3)) -> (N,) bool`` for one sonar pose.

    A point is visible when its range lies in [range_min_m - margin, range_max_m + margin],
    |azimuth| <= fov/2 and, if ``vertical_fov_rad`` is given, |elevation| <= vertical/2
    (all in the sonar frame). ``margin_m`` widens range and, at the point's range, the
    angular limits, so anchors straddling the fan edge count as visible.
    """
    R_nb = rot_from_euler(*np.asarray(rpy_rad, dtype=float))
    R_ns = R_nb @ sonar_to_body_rotation(mount_rpy_rad)
    origin = np.asarray(pos_ned, dtype=float) + R_nb @ np.asarray(mount_pos_body_m, dtype=float)
    half_h = 0.5 * fov_rad
    half_v = None if vertical_fov_rad is None else 0.5 * vertical_fov_rad

    def visible(points_ned: FloatArray) -> NDArray[np.bool_]:
        p_s = (np.asarray(points_ned, dtype=float).reshape(-1, 3) - origin) @ R_ns
        r, a, e = sonar_to_spherical(p_s)
        slack = margin_m / np.maximum(r, 1e-9)
        ok = (r >= range_min_m - margin_m) & (r <= range_max_m + margin_m)
        ok &= np.abs(a) <= half_h + slack
        if half_v is not None:
            ok &= np.abs(e) <= half_v + slack
        return ok

    return visible
