"""FLS polar measurements -> points in the sonar, body and NED frames (paper 000, eqs. 3-6).

The sonar frame, its mount rotation and the spherical <-> Cartesian mapping are those of
:mod:`autonomy.sonar_frame` (re-exported here). The image keeps (r, a) only: eq. 4 takes
``phi = 0``; eqs. 5-6 recover ``phi`` from the altitude ``h`` assuming a flat seabed,
``r sin(gamma + phi) = h`` for a sonar tilted down by ``gamma`` on a level vehicle looking straight ahead. :func:`flat_seabed_elevation`
solves the same condition for any azimuth and attitude (it reduces to eq. 5 at ``a = 0``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.sonar_frame import sonar_to_body_rotation, sonar_to_spherical, spherical_to_sonar

FloatArray = NDArray[np.float64]

__all__ = [
    "flat_seabed_elevation",
    "flat_seabed_point_sonar",
    "planar_point_sonar",
    "sonar_to_body_rotation",
    "sonar_to_spherical",
    "spherical_to_sonar",
    "tilt_level_flat_seabed_elevation",
]


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
