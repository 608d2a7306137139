"""The navigation filter's noise model taken from the simulated sensors' configs.

The onboard filter (:class:`autonomy.navigation.NavNoiseModel`) holds plain numbers; in the
simulator they are those of the sensors it simulates, so the filter's model matches what
the sensors do.
"""

from __future__ import annotations

import math

import numpy as np

from autonomy.navigation.dvl_geometry import janus_beam_dirs_body
from autonomy.navigation.noise_model import NavNoiseModel
from scenarios.config.nav_sensors import AltimeterConfig, DepthConfig, DvlConfig, GpsConfig, ImuConfig


def nav_noise_model(
    imu: ImuConfig | None = None,
    dvl: DvlConfig | None = None,
    depth: DepthConfig | None = None,
    gps: GpsConfig | None = None,
    altimeter: AltimeterConfig | None = None,
) -> NavNoiseModel:
    """Noise model matching the given sensor configs (the default config where ``None``)."""
    imu, dvl, depth, gps = imu or ImuConfig(), dvl or DvlConfig(), depth or DepthConfig(), gps or GpsConfig()
    altimeter = altimeter or AltimeterConfig()
    rp_noise, rp_bias = math.radians(imu.roll_pitch_noise_deg), math.radians(imu.roll_pitch_bias_deg)
    return NavNoiseModel(
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
        dvl_range_noise_m=dvl.range_noise_m,
        altimeter_noise_m=altimeter.noise_m,
        altimeter_noise_frac_range=altimeter.noise_frac_range,
    )
