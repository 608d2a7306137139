"""Ground-truth vehicle state snapshot handed to sensors each time they fire, and the state
between two physics steps (:func:`interpolate_truth`) for a sensor firing between them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.frames import cross3, euler_from_rot, quat_from_rot, rot_from_quat

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class VehicleTruth:
    """True vehicle state at time ``t_s``.

    Attributes:
        pos_ned: (3,) body-origin position in NED, m.
        R_nb: (3, 3) body(FRD)->NED rotation.
        rpy_rad: (3,) roll, pitch, yaw.
        nu: (6,) body velocity [u, v, w, p, q, r] (m/s, rad/s), over ground.
        nu_dot: (6,) body-frame acceleration d(nu)/dt.
        current_ned: (3,) water current at the vehicle, m/s.
    """

    t_s: float
    pos_ned: FloatArray
    R_nb: FloatArray
    rpy_rad: FloatArray
    nu: FloatArray
    nu_dot: FloatArray
    current_ned: FloatArray

    @property
    def vel_body_mps(self) -> FloatArray:
        return self.nu[:3]

    @property
    def rate_body_radps(self) -> FloatArray:
        return self.nu[3:]

    @property
    def vel_ned_mps(self) -> FloatArray:
        return self.R_nb @ self.nu[:3]

    @property
    def depth_m(self) -> float:
        return float(self.pos_ned[2])

    def point_ned(self, offset_body_m: FloatArray) -> FloatArray:
        """NED position of a point fixed on the hull at ``offset_body_m`` (FRD)."""
        return self.pos_ned + self.R_nb @ np.asarray(offset_body_m, dtype=float)

    def point_vel_body(self, offset_body_m: FloatArray) -> FloatArray:
        """(3,) velocity over ground of the hull point at ``offset_body_m`` (FRD, m), in FRD,
        m/s: ``v + omega x r``."""
        return self.nu[:3] + cross3(self.nu[3:], offset_body_m)

    def point_accel_body(self, offset_body_m: FloatArray) -> FloatArray:
        """(3,) inertial acceleration of the hull point at ``offset_body_m`` (FRD, m), in FRD,
        m/s^2: ``v_dot + omega x v + omega_dot x r + omega x (omega x r)`` (``v`` is the body
        velocity over ground, so ``omega x v`` is the transport term)."""
        # in Python floats (runs at the IMU rate), the same operations in the same order as
        # v_dot + cross3(omega, v) + cross3(omega_dot, r) + cross3(omega, cross3(omega, r))
        u, v, w, p, q, r = self.nu.tolist()
        ud, vd, wd, pd, qd, rd = self.nu_dot.tolist()
        x, y, z = offset_body_m.tolist() if isinstance(offset_body_m, np.ndarray) else offset_body_m
        wx, wy, wz = q * z - r * y, r * x - p * z, p * y - q * x  # omega x r
        return np.array([ud + (q * w - r * v) + (qd * z - rd * y) + (q * wz - r * wy),
                         vd + (r * u - p * w) + (rd * x - pd * z) + (r * wx - p * wz),
                         wd + (p * v - q * u) + (pd * y - qd * x) + (p * wy - q * wx)])


def _slerp(q0: FloatArray, q1: FloatArray, f: float) -> FloatArray:
    """Unit quaternion a fraction ``f`` of the way from ``q0`` to ``q1`` along the shorter arc."""
    dot = float(q0 @ q1)
    if dot < 0.0:
        q1, dot = -q1, -dot
    if dot > 1.0 - 1e-12:  # (almost) the same attitude: the chord is the arc
        q = q0 + f * (q1 - q0)
        return q / np.linalg.norm(q)
    theta = np.arccos(dot)
    s = np.sin(theta)
    return (np.sin((1.0 - f) * theta) / s) * q0 + (np.sin(f * theta) / s) * q1


def interpolate_truth(a: VehicleTruth, b: VehicleTruth, t_s: float) -> VehicleTruth:
    """The true state at ``t_s`` between the snapshots ``a`` and ``b`` of two physics steps.

    Position: the cubic Hermite curve through both positions with both NED velocities
    (exact for a constant acceleration); attitude: the rotation from ``R_a`` to ``R_b``
    taken in proportion (quaternion slerp; exact for a constant body rate); body velocity,
    acceleration and the current: linear (exact for a constant acceleration). The error of
    an arbitrary smooth motion is of the order of its next derivative times ``dt^2`` to
    ``dt^4`` over one physics step ``dt``.

    Args:
        a, b: snapshots at ``a.t_s < b.t_s``.
        t_s: time in ``[a.t_s, b.t_s]``, s.

    Raises:
        ValueError: ``a`` is not earlier than ``b``, or ``t_s`` lies outside them.
    """
    ta, tb = float(a.t_s), float(b.t_s)
    span = tb - ta
    if not span > 0.0:
        raise ValueError(f"interpolate_truth: the first snapshot ({ta} s) must be earlier than the second ({tb} s)")
    f = (float(t_s) - ta) / span
    if not -1e-9 <= f <= 1.0 + 1e-9:
        raise ValueError(f"interpolate_truth: t_s = {t_s} s is outside [{ta}, {tb}] s")
    f = min(max(f, 0.0), 1.0)
    f2, f3 = f * f, f * f * f
    h00, h10, h01, h11 = 2 * f3 - 3 * f2 + 1.0, f3 - 2 * f2 + f, -2 * f3 + 3 * f2, f3 - f2
    pos = h00 * a.pos_ned + h10 * span * a.vel_ned_mps + h01 * b.pos_ned + h11 * span * b.vel_ned_mps
    R = rot_from_quat(_slerp(quat_from_rot(a.R_nb), quat_from_rot(b.R_nb), f))
    g = 1.0 - f
    return VehicleTruth(
        t_s=float(t_s),
        pos_ned=pos,
        R_nb=R,
        rpy_rad=euler_from_rot(R),
        nu=g * a.nu + f * b.nu,
        nu_dot=g * a.nu_dot + f * b.nu_dot,
        current_ned=g * np.asarray(a.current_ned, dtype=float) + f * np.asarray(b.current_ned, dtype=float),
    )
