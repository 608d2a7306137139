"""Reference frames and rotations (pure numpy).

Conventions used throughout auvsim:

* World frame: **NED** (x north, y east, z down), metres. The MuJoCo world *is* the
  NED frame, so positions read from MuJoCo are ``pos_ned`` without conversion.
* Body frame: **FRD** (x forward, y starboard, z down), Fossen's convention.
* Euler angles: roll-pitch-yaw ``(phi, theta, psi)`` in radians, ZYX order, so
  ``R_nb = Rz(psi) @ Ry(theta) @ Rx(phi)`` maps body vectors into NED.
* Quaternions: scalar-first ``(w, x, y, z)``, as MuJoCo stores them.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def cross3(a: FloatArray, b: FloatArray) -> FloatArray:
    """Cross product ``a x b`` of two (3,) vectors, same frame in and out.

    Written out in Python floats because ``np.cross`` (and numpy scalar arithmetic) is slow
    for single vectors.
    """
    a0, a1, a2 = a.tolist() if isinstance(a, np.ndarray) else a
    b0, b1, b2 = b.tolist() if isinstance(b, np.ndarray) else b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def skew(v: ArrayLike) -> FloatArray:
    """Skew-symmetric matrix S(v) with S(v) @ w == cross(v, w). Shape (3, 3)."""
    x, y, z = np.asarray(v, dtype=float)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


# The functions of one angle or one rotation below take Python scalars through ``math``:
# for single rotations numpy's per-call overhead costs several times the arithmetic.


def rot_x(angle_rad: float) -> FloatArray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle_rad: float) -> FloatArray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle_rad: float) -> FloatArray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rot_from_euler(roll_rad: float, pitch_rad: float, yaw_rad: float) -> FloatArray:
    """Body(FRD)->NED rotation ``R_nb`` from ZYX Euler angles. Shape (3, 3).

    ``Rz(yaw) Ry(pitch) Rx(roll)`` multiplied out ([Fossen2021] section 2.2.1)."""
    cf, sf = math.cos(roll_rad), math.sin(roll_rad)
    ct, st = math.cos(pitch_rad), math.sin(pitch_rad)
    cp, sp = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[cp * ct, -sp * cf + cp * st * sf, sp * sf + cp * cf * st],
                     [sp * ct, cp * cf + sf * st * sp, -cp * sf + st * sp * cf],
                     [-st, ct * sf, ct * cf]])


def euler_from_rot(R_nb: ArrayLike) -> FloatArray:
    """ZYX Euler angles ``[roll, pitch, yaw]`` (rad) of a body->NED rotation."""
    R = np.asarray(R_nb, dtype=float)
    (r00, _, _), (r10, _, _), (r20, r21, r22) = R.tolist()
    pitch = -math.asin(min(max(r20, -1.0), 1.0))
    return np.array([math.atan2(r21, r22), pitch, math.atan2(r10, r00)])


def quat_from_rot(R: ArrayLike) -> FloatArray:
    """Unit quaternion ``(w, x, y, z)`` of a rotation matrix."""
    R = np.asarray(R, dtype=float)
    tr = np.trace(R)
    if tr > 0.0:
        s = 2.0 * np.sqrt(tr + 1.0)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s]
    q = np.asarray(q)
    return q / np.linalg.norm(q) * (1.0 if q[0] >= 0.0 else -1.0)


def rot_from_quat(q: ArrayLike) -> FloatArray:
    """Rotation matrix of a quaternion ``(w, x, y, z)`` (normalised first)."""
    w, x, y, z = np.asarray(q, dtype=float).tolist()
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def quat_from_euler(roll_rad: float, pitch_rad: float, yaw_rad: float) -> FloatArray:
    return quat_from_rot(rot_from_euler(roll_rad, pitch_rad, yaw_rad))


def wrap_angle(angle_rad: ArrayLike) -> FloatArray | float:
    """Wrap angle(s) to [-pi, pi) (a Python float for a float, else an array)."""
    if isinstance(angle_rad, float):
        return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi
    return (np.asarray(angle_rad) + np.pi) % (2.0 * np.pi) - np.pi


def euler_rate_matrix(roll_rad: float, pitch_rad: float) -> FloatArray:
    """T(Theta) mapping body rates [p, q, r] to Euler rates (Fossen eq. 2.41). (3, 3)."""
    cphi, sphi = math.cos(roll_rad), math.sin(roll_rad)
    cth, tth = math.cos(pitch_rad), math.tan(pitch_rad)
    return np.array(
        [[1.0, sphi * tth, cphi * tth], [0.0, cphi, -sphi], [0.0, sphi / cth, cphi / cth]]
    )


# -- ROS conventions (REP 103 / REP 105) -----------------------------------------------
# ROS uses ENU world frames (x east, y north, z up) and FLU body frames (x forward, y left,
# z up). Both conversions are fixed axis permutations/reflections, each its own inverse.

#: (3, 3) maps NED vectors to ENU: ``v_enu = R_ENU_NED @ v_ned`` (swap x/y, negate z).
R_ENU_NED: FloatArray = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: (3, 3) maps FRD vectors to FLU: ``v_flu = R_FLU_FRD @ v_frd`` (negate y and z).
R_FLU_FRD: FloatArray = np.diag([1.0, -1.0, -1.0])


def enu_from_ned(v_ned: ArrayLike) -> FloatArray:
    """World vectors/points (..., 3) from NED to ENU (m, m/s, ...): ``(y, x, -z)``."""
    v = np.asarray(v_ned, dtype=float)
    return v @ R_ENU_NED.T


def flu_from_frd(v_frd: ArrayLike) -> FloatArray:
    """Body vectors (..., 3) from FRD to FLU (velocities, rates, forces): ``(x, -y, -z)``."""
    v = np.asarray(v_frd, dtype=float)
    return v @ R_FLU_FRD.T


def rot_enu_flu(R_nb: ArrayLike) -> FloatArray:
    """(3, 3) FLU-body -> ENU rotation of a body whose FRD -> NED rotation is ``R_nb``."""
    return R_ENU_NED @ np.asarray(R_nb, dtype=float) @ R_FLU_FRD


def cov_enu_from_ned(cov_ned: ArrayLike) -> FloatArray:
    """(3, 3) covariance of a NED vector expressed in ENU (m^2): ``A C A^T``."""
    return R_ENU_NED @ np.asarray(cov_ned, dtype=float) @ R_ENU_NED.T


def quat_xyzw(q_wxyz: ArrayLike) -> FloatArray:
    """Scalar-last ``(x, y, z, w)`` order (ROS, rerun) of a scalar-first quaternion (4,)."""
    w, x, y, z = np.asarray(q_wxyz, dtype=float)
    return np.array([x, y, z, w])
