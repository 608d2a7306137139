"""FLS polar measurements -> points in the sonar, body and NED frames (paper 000, eqs. 3-6).

Sonar frame: x along the boresight, y starboard, z down. A point at range ``r``, azimuth
``a`` (starboard > 0) and elevation ``phi`` (down > 0) is ``r [cos a cos phi, sin a cos phi,
sin phi]``. The image keeps (r, a) only: eq. 4 takes ``phi = 0``; eqs. 5-6 recover ``phi``
from the altitude ``h`` assuming a flat seabed, ``r sin(gamma + phi) = h`` for a sonar tilted
down by ``gamma`` on a level vehicle looking straight ahead. :func:`flat_seabed_elevation`
solves the same condition for any azimuth and attitude (it reduces to eq. 5 at ``a = 0``).

Mount convention: ``mount_rpy_rad = (roll, tilt, yaw)`` of the sonar w.r.t. the body with the
tilt positive *down*, so the boresight in body FRD is ``[cos tilt, 0, sin tilt]``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_x, rot_y, rot_z

FloatArray = NDArray[np.float64]


def sonar_to_body_rotation(mount_rpy_rad: ArrayLike) -> FloatArray:
    """Sonar->body rotation ``R_bs`` (3, 3) from (roll, tilt down > 0, yaw) in radians."""
    roll, tilt, yaw = np.asarray(mount_rpy_rad, dtype=float)
    return rot_z(yaw) @ rot_y(-tilt) @ rot_x(roll)


def spherical_to_sonar(range_m: ArrayLike, azimuth_rad: ArrayLike, elevation_rad: ArrayLike) -> FloatArray:
    """Eqs. 3/6: (r, a, phi) -> sonar-frame points, shape (..., 3), metres."""
    r = np.asarray(range_m, dtype=float)
    a = np.asarray(azimuth_rad, dtype=float)
    e = np.asarray(elevation_rad, dtype=float)
    ce = np.cos(e)
    return np.stack(np.broadcast_arrays(r * np.cos(a) * ce, r * np.sin(a) * ce, r * np.sin(e)), axis=-1)


def sonar_to_spherical(p_sonar: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Inverse of :func:`spherical_to_sonar`: points (..., 3) -> (range, azimuth, elevation)."""
    p = np.asarray(p_sonar, dtype=float)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    return np.sqrt(x * x + y * y + z * z), np.arctan2(y, x), np.arctan2(z, np.hypot(x, y))


def planar_point_sonar(range_m: ArrayLike, azimuth_rad: ArrayLike) -> FloatArray:
    """Eq. 4: the 2-D approximation, elevation zero. Shape (..., 3)."""
    return spherical_to_sonar(range_m, azimuth_rad, 0.0)


def flat_seabed_elevation(
    range_m: float, azimuth_rad: float, altitude_m: float, R_ns: ArrayLike
) -> float:
    """Elevation (rad, down > 0) at which the arc of (r, a) meets a flat seabed.

    Solves ``down(R_ns @ p_sonar(r, a, phi)) = altitude_m`` where ``altitude_m`` is the height
    of the sonar head above the seabed and ``R_ns`` the sonar->NED rotation (3, 3). Of the two
    roots the one nearer the boresight is returned; a range shorter than the geometry allows
    (no intersection) gives the elevation of the arc's lowest point.
    """
    R = np.asarray(R_ns, dtype=float)
    # down component = r (A cos phi + B sin phi) = r rho sin(phi + psi)
    A = R[2, 0] * np.cos(azimuth_rad) + R[2, 1] * np.sin(azimuth_rad)
    B = R[2, 2]
    rho = float(np.hypot(A, B))
    psi = float(np.arctan2(A, B))
    s = float(np.clip(altitude_m / (range_m * rho), -1.0, 1.0))
    return float(np.arcsin(s) - psi)


def flat_seabed_point_sonar(
    range_m: float, azimuth_rad: float, altitude_m: float, R_ns: ArrayLike
) -> FloatArray:
    """Eqs. 5-6: sonar-frame point (3,) of a seabed return at (r, a)."""
    phi = flat_seabed_elevation(range_m, azimuth_rad, altitude_m, R_ns)
    return spherical_to_sonar(range_m, azimuth_rad, phi)


def tilt_level_flat_seabed_elevation(range_m: float, altitude_m: float, tilt_rad: float) -> float:
    """Eq. 5 verbatim: ``r sin(gamma + phi) = h`` solved for ``phi`` (level vehicle, a = 0)."""
    return float(np.arcsin(np.clip(altitude_m / range_m, -1.0, 1.0)) - tilt_rad)
