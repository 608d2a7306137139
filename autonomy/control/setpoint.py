"""Setpoint handed from guidance to the autopilots."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Setpoint:
    """Desired motion for the 4 controlled DOFs (surge, sway, heave, yaw).

    Exactly one of ``depth_m`` / ``altitude_m`` is set: the vertical autopilot holds depth
    (NED z, m, down positive) or altitude above the seabed (m).

    Attributes:
        speed_mps: surge speed through the water column as measured by the nav (body x), m/s.
        heading_rad: yaw in NED (0 north, pi/2 east), rad.
        depth_m: desired depth, m, or None.
        altitude_m: desired altitude, m, or None.
        sway_mps: desired body sway speed, m/s (0 for surveys).
    """

    speed_mps: float
    heading_rad: float
    depth_m: float | None = None
    altitude_m: float | None = None
    sway_mps: float = 0.0

    def __post_init__(self) -> None:
        if (self.depth_m is None) == (self.altitude_m is None):
            raise ValueError("Setpoint needs exactly one of depth_m or altitude_m")
        for name in ("speed_mps", "heading_rad", "sway_mps"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"Setpoint.{name} must be finite, got {getattr(self, name)}")
        if self.depth_m is not None and not (math.isfinite(self.depth_m) and self.depth_m >= 0.0):
            raise ValueError(f"Setpoint.depth_m must be finite and >= 0, got {self.depth_m}")
        if self.altitude_m is not None and not (math.isfinite(self.altitude_m) and self.altitude_m > 0.0):
            raise ValueError(f"Setpoint.altitude_m must be finite and > 0, got {self.altitude_m}")
