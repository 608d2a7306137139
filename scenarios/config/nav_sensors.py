"""Navigation sensor configs: IMU/AHRS (+ FOG heading), DVL, depth, altimeter, GPS.

Defaults follow FeelHippo's suite (docs/references.md [P000] Table IV): Orientus AHRS with a KVH DSP 1760
single-axis FOG for heading, Nortek DVL1000 (bottom track + pressure), surface-only GPS.
Noise figures are our estimates of datasheet-class values, not measured on the vehicle.
All noise terms are 1-sigma; "bias" terms are the sigma of a per-run constant drawn once.
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field

from scenarios.config.sensor import SensorConfig, sensor_config

Latency = Field(0.0, ge=0.0, le=5.0, description="delay from sampling to delivery, s")


@sensor_config
class ImuConfig(SensorConfig):
    """AHRS/IMU: attitude, body rates and specific force.

    ``heading_source='fog'`` integrates a fibre-optic gyro: heading error is an alignment bias
    plus a random walk. ``'ahrs'`` uses the magnetometer heading: a larger constant bias plus
    larger white noise, no drift.
    """

    kind: Literal["imu"] = "imu"

    rate_hz: float = Field(100.0, gt=0.0, le=1000.0)
    latency_s: float = Latency
    heading_source: Literal["fog", "ahrs"] = "fog"
    roll_pitch_noise_deg: float = Field(0.1, ge=0.0, le=10.0, description="white, per sample")
    roll_pitch_bias_deg: float = Field(0.1, ge=0.0, le=10.0, description="per-run constant")
    fog_heading_noise_deg: float = Field(0.02, ge=0.0, le=10.0)
    fog_heading_bias_deg: float = Field(0.5, ge=0.0, le=30.0, description="alignment error")
    fog_heading_random_walk_deg_per_sqrt_h: float = Field(
        0.05, ge=0.0, le=100.0, description="angle random walk + bias instability, lumped"
    )
    ahrs_heading_noise_deg: float = Field(0.5, ge=0.0, le=30.0)
    ahrs_heading_bias_deg: float = Field(1.0, ge=0.0, le=30.0, description="magnetic bias")
    gyro_noise_dps: float = Field(0.03, ge=0.0, le=100.0)
    gyro_bias_dps: float = Field(0.01, ge=0.0, le=100.0)
    accel_noise_mps2: float = Field(0.01, ge=0.0, le=10.0)
    accel_bias_mps2: float = Field(0.005, ge=0.0, le=10.0)

    @property
    def heading_noise_rad(self) -> float:
        deg = self.fog_heading_noise_deg if self.heading_source == "fog" else self.ahrs_heading_noise_deg
        return math.radians(deg)

    @property
    def heading_bias_rad(self) -> float:
        deg = self.fog_heading_bias_deg if self.heading_source == "fog" else self.ahrs_heading_bias_deg
        return math.radians(deg)

    @property
    def heading_random_walk_rad_per_sqrt_s(self) -> float:
        if self.heading_source != "fog":
            return 0.0
        return math.radians(self.fog_heading_random_walk_deg_per_sqrt_h) / 60.0


@sensor_config
class DvlConfig(SensorConfig):
    """Janus 4-beam bottom-tracking DVL. Per-beam radial velocity noise is
    ``beam_noise_mps + noise_frac_speed * |v|``; a per-run scale error (sound speed) multiplies
    all beams. Lock needs ``min_valid_beams`` beam hits within ``max_altitude_m`` and a seabed
    slope (plane fitted to the beam footprints) of at most ``max_slope_deg``."""

    kind: Literal["dvl"] = "dvl"

    rate_hz: float = Field(5.0, gt=0.0, le=100.0)
    latency_s: float = Latency
    beam_angle_deg: float = Field(30.0, gt=0.0, lt=60.0, description="beam tilt from vertical")
    beam_azimuth_offset_deg: float = Field(45.0, ge=0.0, lt=90.0, description="first beam vs bow")
    min_altitude_m: float = Field(0.3, ge=0.0, le=10.0)
    max_altitude_m: float = Field(50.0, gt=0.0, le=1000.0)
    max_slope_deg: float = Field(30.0, gt=0.0, le=80.0)
    max_incidence_deg: float = Field(80.0, gt=0.0, le=90.0, description="grazing-angle cut per beam")
    min_valid_beams: int = Field(3, ge=3, le=4)
    beam_noise_mps: float = Field(0.002, ge=0.0, le=1.0)
    noise_frac_speed: float = Field(0.004, ge=0.0, le=0.5)
    scale_error: float = Field(0.002, ge=0.0, le=0.1, description="per-run scale factor sigma")
    range_noise_m: float = Field(0.01, ge=0.0, le=5.0)
    dropout_prob: float = Field(0.02, ge=0.0, le=1.0)


@sensor_config
class DepthConfig(SensorConfig):
    """Pressure depth sensor (the DVL1000's on FeelHippo)."""

    kind: Literal["depth"] = "depth"

    rate_hz: float = Field(10.0, gt=0.0, le=100.0)
    latency_s: float = Latency
    noise_m: float = Field(0.02, ge=0.0, le=10.0)


@sensor_config
class AltimeterConfig(SensorConfig):
    """Single-beam echo sounder looking along body +z (down)."""

    kind: Literal["altimeter"] = "altimeter"

    rate_hz: float = Field(5.0, gt=0.0, le=100.0)
    latency_s: float = Latency
    min_range_m: float = Field(0.1, ge=0.0, le=10.0)
    max_range_m: float = Field(30.0, gt=0.0, le=1000.0)
    noise_m: float = Field(0.01, ge=0.0, le=10.0)
    noise_frac_range: float = Field(0.002, ge=0.0, le=0.5)
    dropout_prob: float = Field(0.0, ge=0.0, le=1.0)


@sensor_config
class GpsConfig(SensorConfig):
    """GPS receiver: fixes only while the antenna is shallower than ``max_antenna_depth_m``."""

    kind: Literal["gps"] = "gps"

    rate_hz: float = Field(1.0, gt=0.0, le=20.0)
    latency_s: float = Latency
    max_antenna_depth_m: float = Field(0.2, ge=0.0, le=5.0)
    noise_m: float = Field(1.0, ge=0.0, le=100.0, description="per horizontal axis")
    dropout_prob: float = Field(0.05, ge=0.0, le=1.0)
