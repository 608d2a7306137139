"""Ground-truth vehicle state snapshot handed to sensors each time they fire."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.frames import cross3

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
