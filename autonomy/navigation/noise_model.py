"""The navigation filter's model of its sensors' noise, built from the sensor configs."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.navigation.dvl_geometry import beam_velocity_covariance, janus_beam_dirs_body
from scenarios.config.nav_sensors import DepthConfig, DvlConfig, GpsConfig, ImuConfig

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class NavNoiseModel:
    """Sensor noise as the filter assumes it (1-sigma, SI units, radians).

    Attributes:
        attitude_noise_rad: (3,) white roll/pitch/yaw noise per AHRS sample.
        attitude_bias_sigma_rad: (3,) prior sigma of the constant attitude bias.
        heading_rw_rad_per_sqrt_s: random-walk density of the heading bias (FOG drift).
        dvl_beam_dirs_body: (4, 3) DVL beam unit vectors, FRD.
        dvl_beam_noise_mps: constant part of the per-beam radial velocity noise.
        dvl_noise_frac_speed: speed-proportional part of the per-beam noise.
        dvl_scale_sigma: prior sigma of the DVL scale-factor error.
        depth_noise_m: depth sensor white noise.
        gps_noise_m: GPS white noise per horizontal axis.
    """

    attitude_noise_rad: FloatArray
    attitude_bias_sigma_rad: FloatArray
    heading_rw_rad_per_sqrt_s: float
    dvl_beam_dirs_body: FloatArray
    dvl_beam_noise_mps: float
    dvl_noise_frac_speed: float
    dvl_scale_sigma: float
    depth_noise_m: float
    gps_noise_m: float

    @classmethod
    def from_sensor_configs(
        cls,
        imu: ImuConfig | None = None,
        dvl: DvlConfig | None = None,
        depth: DepthConfig | None = None,
        gps: GpsConfig | None = None,
    ) -> NavNoiseModel:
        """Noise model matching the given sensor configs (defaults where ``None``)."""
        imu, dvl, depth, gps = imu or ImuConfig(), dvl or DvlConfig(), depth or DepthConfig(), gps or GpsConfig()
        rp_noise, rp_bias = math.radians(imu.roll_pitch_noise_deg), math.radians(imu.roll_pitch_bias_deg)
        return cls(
            attitude_noise_rad=np.array([rp_noise, rp_noise, imu.heading_noise_rad]),
            attitude_bias_sigma_rad=np.array([rp_bias, rp_bias, imu.heading_bias_rad]),
            heading_rw_rad_per_sqrt_s=imu.heading_random_walk_rad_per_sqrt_s,
            dvl_beam_dirs_body=janus_beam_dirs_body(
                math.radians(dvl.beam_angle_deg), math.radians(dvl.beam_azimuth_offset_deg)
            ),
            dvl_beam_noise_mps=dvl.beam_noise_mps,
            dvl_noise_frac_speed=dvl.noise_frac_speed,
            dvl_scale_sigma=dvl.scale_error,
            depth_noise_m=depth.noise_m,
            gps_noise_m=gps.noise_m,
        )

    def dvl_velocity_cov(self, vel_meas_body_mps: FloatArray, beams_used: NDArray[np.bool_] | None = None) -> FloatArray:
        """Covariance (3, 3) of a DVL velocity solved from the ``beams_used`` (default all)."""
        dirs = self.dvl_beam_dirs_body if beams_used is None else self.dvl_beam_dirs_body[beams_used]
        sigma = self.dvl_beam_noise_mps + self.dvl_noise_frac_speed * float(np.linalg.norm(vel_meas_body_mps))
        return beam_velocity_covariance(dirs, sigma)
