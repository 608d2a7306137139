"""The navigation filter's model of its sensors' noise (plain numbers).

The vehicle integration fills it from its sensors' data sheets or, in the simulator, from the
simulated sensors' configs (:func:`sim.sensors.nav_noise.nav_noise_model`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.navigation.dvl_geometry import beam_velocity_covariance

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

    def dvl_velocity_cov(self, vel_meas_body_mps: FloatArray, beams_used: NDArray[np.bool_] | None = None) -> FloatArray:
        """Covariance (3, 3) of a DVL velocity solved from the ``beams_used`` (default all)."""
        dirs = self.dvl_beam_dirs_body if beams_used is None else self.dvl_beam_dirs_body[beams_used]
        sigma = self.dvl_beam_noise_mps + self.dvl_noise_frac_speed * float(np.linalg.norm(vel_meas_body_mps))
        return beam_velocity_covariance(dirs, sigma)
