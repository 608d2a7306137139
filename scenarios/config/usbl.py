"""USBL config: range, bearing and elevation of a transponder with range-growing noise,
multipath outliers, dropouts and acoustic travel-time latency (paper 004, docs/references.md
[P004]; noise figures are our estimates of a compact modem/USBL class such as the Seatrac
X150 used in the paper's trials, not datasheet values)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from scenarios.config.base import Vec3
from scenarios.config.sensor import SensorConfig, sensor_config


@sensor_config
class UsblConfig(SensorConfig):
    """An USBL head on the hull interrogating one transponder.

    ``transponder``: ``"beacon"`` for a fixed beacon at ``beacon_pos_ned`` (navigation
    fixes), or the name of a scene object (a mover such as ``diver``) carrying it.
    Noise (1 sigma): range ``range_sigma_m + range_sigma_frac * range``; bearing and
    elevation ``angle_sigma_deg + angle_sigma_deg_per_100m * range / 100`` (both grow with
    distance). A fix is missing with ``dropout_prob``; otherwise with ``outlier_prob`` it is
    a multipath return: the range is longer by U(0, ``outlier_extra_range_m``) and the
    angles are off by N(0, ``outlier_angle_sigma_deg``). Delivery latency:
    ``latency_s + turnaround_s + 2 * range / sound_speed_mps``.
    """

    kind: Literal["usbl"] = "usbl"

    rate_hz: float = Field(0.5, ge=1.0 / 3.0, le=1.0, description="fix every 1-3 s")
    latency_s: float = Field(0.2, ge=0.0, le=5.0, description="processing delay added to the travel time, s")
    transponder: str = Field("beacon", min_length=1, description='"beacon" or the scene object carrying it')
    beacon_pos_ned: Vec3 = Field((0.0, 0.0, 0.0), description="known beacon position (transponder: beacon), m")
    sound_speed_mps: float = Field(1500.0, ge=1400.0, le=1600.0)
    turnaround_s: float = Field(0.0, ge=0.0, le=2.0, description="transponder reply delay, s")
    max_range_m: float = Field(1000.0, gt=0.0, le=10000.0, description="no fix beyond, m")
    range_sigma_m: float = Field(0.1, ge=0.0, le=50.0)
    range_sigma_frac: float = Field(0.01, ge=0.0, le=0.5, description="range sigma per metre of range")
    angle_sigma_deg: float = Field(1.0, ge=0.0, le=45.0)
    angle_sigma_deg_per_100m: float = Field(1.0, ge=0.0, le=45.0)
    outlier_prob: float = Field(0.03, ge=0.0, le=1.0, description="multipath fixes")
    outlier_extra_range_m: float = Field(5.0, ge=0.0, le=500.0)
    outlier_angle_sigma_deg: float = Field(10.0, ge=0.0, le=180.0)
    dropout_prob: float = Field(0.1, ge=0.0, le=1.0)

    def range_sigma_at(self, range_m: float) -> float:
        """Range noise sigma (m) at ``range_m``."""
        return self.range_sigma_m + self.range_sigma_frac * range_m

    def angle_sigma_deg_at(self, range_m: float) -> float:
        """Bearing/elevation noise sigma (deg) at ``range_m``."""
        return self.angle_sigma_deg + self.angle_sigma_deg_per_100m * range_m / 100.0
