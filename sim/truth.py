"""Ground-truth vehicle state snapshot handed to sensors each time they fire."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

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
