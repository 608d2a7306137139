"""The sonar frame: its rotation from the body and the directions of its rays (pure numpy).

One convention for every sonar on the vehicle (forward-looking, scanning, side-scan), used
on board by target geolocalisation and by the simulator to cast the sonar's rays.

Sonar frame: x along the boresight, y to starboard, z down (right-handed, like body FRD).
A point at slant range ``r``, azimuth ``a`` (positive to starboard) and elevation ``phi``
(positive *down*) is ``r [cos a cos phi, sin a cos phi, sin phi]``
(paper 000, eqs. 3 and 6, in ``docs/references.md``).

Mount: ``mount_rpy_rad = (roll, tilt, yaw)`` of the sonar frame with respect to the body,
radians, with the tilt positive when the boresight points *down*: the sonar->body rotation
is ``R_bs = Rz(yaw) Ry(-tilt) Rx(roll)`` (ZYX Euler angles, pitch = -tilt), so the boresight
in body FRD is ``[cos tilt, 0, sin tilt]`` at zero roll and yaw. A side-scan transducer
looking to starboard and depressed by ``d`` is mounted at ``(0, d, pi/2)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_from_euler

FloatArray = NDArray[np.float64]


def mount_euler_zyx(mount_rpy_rad: ArrayLike) -> FloatArray:
    """ZYX Euler angles ``(roll, pitch, yaw)`` of the sonar->body rotation from a mount.

    Args:
        mount_rpy_rad: (..., 3) ``(roll, tilt down > 0, yaw)`` in radians.

    Returns:
        (..., 3) ``(roll, -tilt, yaw)``: the angles :func:`autonomy.frames.rot_from_euler`
        (or any ZYX composition) turns into ``R_bs``.

    Raises:
        ValueError: if the last axis is not of length 3.
    """
    m = np.asarray(mount_rpy_rad, dtype=float)
    if m.shape[-1:] != (3,):
        raise ValueError(f"mount_rpy_rad must have shape (..., 3), got {m.shape}")
    out = m.copy()
    out[..., 1] = -m[..., 1]
    return out


def sonar_to_body_rotation(mount_rpy_rad: ArrayLike) -> FloatArray:
    """Sonar->body rotation ``R_bs`` (3, 3) from a mount ``(roll, tilt down > 0, yaw)`` (rad).

    Raises:
        ValueError: if ``mount_rpy_rad`` does not hold three angles.
    """
    m = np.asarray(mount_rpy_rad, dtype=float)
    if m.shape != (3,):
        raise ValueError(f"mount_rpy_rad must have shape (3,), got {m.shape}")
    roll, pitch, yaw = mount_euler_zyx(m)
    return rot_from_euler(roll, pitch, yaw)


def spherical_to_sonar(range_m: ArrayLike, azimuth_rad: ArrayLike, elevation_rad: ArrayLike) -> FloatArray:
    """Points in the sonar frame from slant range (m), azimuth and elevation (rad).

    Inputs broadcast together; returns (..., 3) metres, ``r [cos a cos phi, sin a cos phi,
    sin phi]``.
    """
    r = np.asarray(range_m, dtype=float)
    a = np.asarray(azimuth_rad, dtype=float)
    e = np.asarray(elevation_rad, dtype=float)
    ce = np.cos(e)
    return np.stack(np.broadcast_arrays(r * np.cos(a) * ce, r * np.sin(a) * ce, r * np.sin(e)), axis=-1)


def sonar_to_spherical(p_sonar: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Inverse of :func:`spherical_to_sonar`: points (..., 3) -> (range m, azimuth rad,
    elevation rad), each of shape (...)."""
    p = np.asarray(p_sonar, dtype=float)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    return np.sqrt(x * x + y * y + z * z), np.arctan2(y, x), np.arctan2(z, np.hypot(x, y))


def ray_directions_sonar(azimuth_rad: ArrayLike, elevation_rad: ArrayLike) -> FloatArray:
    """Unit ray directions (..., 3) in the sonar frame for broadcast azimuths and elevations (rad).

    :func:`spherical_to_sonar` at unit range (the same products, written into one array).
    """
    a, e = np.broadcast_arrays(np.asarray(azimuth_rad, dtype=float), np.asarray(elevation_rad, dtype=float))
    out = np.empty(a.shape + (3,))
    ce = np.cos(e)
    np.multiply(np.cos(a), ce, out=out[..., 0])
    np.multiply(np.sin(a), ce, out=out[..., 1])
    np.sin(e, out=out[..., 2])
    return out
