"""Navigation sensor configs: IMU/AHRS, DVL, depth, altimeter, GPS."""

from __future__ import annotations

from pydantic import Field

from scenarios.config.base import StrictModel


class ImuConfig(StrictModel):
    rate_hz: float = Field(100.0, gt=0.0, le=1000.0)


class DvlConfig(StrictModel):
    rate_hz: float = Field(5.0, gt=0.0, le=100.0)


class DepthConfig(StrictModel):
    rate_hz: float = Field(10.0, gt=0.0, le=100.0)


class AltimeterConfig(StrictModel):
    rate_hz: float = Field(5.0, gt=0.0, le=100.0)


class GpsConfig(StrictModel):
    rate_hz: float = Field(1.0, gt=0.0, le=20.0)
