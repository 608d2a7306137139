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
        dvl_range_noise_m: white noise of each DVL beam's slant range.
        altimeter_noise_m: constant part of the altimeter range noise.
        altimeter_noise_frac_range: range-proportional part of the altimeter range noise.
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
    dvl_range_noise_m: float = 0.01
    altimeter_noise_m: float = 0.01
    altimeter_noise_frac_range: float = 0.002

    def dvl_velocity_cov(self, vel_meas_body_mps: FloatArray, beams_used: NDArray[np.bool_] | None = None) -> FloatArray:
        """Covariance (3, 3) of a DVL velocity solved from the ``beams_used`` (default all)."""
        dirs = self.dvl_beam_dirs_body if beams_used is None else self.dvl_beam_dirs_body[beams_used]
        sigma = self.dvl_beam_noise_mps + self.dvl_noise_frac_speed * float(np.linalg.norm(vel_meas_body_mps))
        return beam_velocity_covariance(dirs, sigma)

    def dvl_altitude_var_m2(self, beam_offsets_ned_m: FloatArray) -> float:
        """Variance (m^2) of the DVL altitude, the depth below the transducer of the
        least-squares plane through its beam footprints.

        Args:
            beam_offsets_ned_m: (n >= 3, 3) footprints of the beams used, relative to the
                transducer, NED m (range times the beam's NED unit vector).

        Each footprint depth carries the range noise projected on the vertical,
        ``dvl_range_noise_m * |d_down|``; the plane's value under the transducer is the
        intercept of ``depth = c + g_n n + g_e e`` with variance ``sigma^2 [(A^T A)^-1]_00``.

        Raises:
            ValueError: for fewer than 3 footprints or footprints on one vertical plane.
        """
        offsets = np.asarray(beam_offsets_ned_m, dtype=float)
        if offsets.ndim != 2 or offsets.shape[0] < 3 or offsets.shape[1] != 3:
            raise ValueError(f"dvl_altitude_var_m2 needs (n >= 3, 3) footprints, got {offsets.shape}")
        ranges = np.linalg.norm(offsets, axis=1)
        down = offsets[:, 2] / ranges
        A = np.column_stack([np.ones(len(offsets)), offsets[:, 0], offsets[:, 1]])
        normal = A.T @ A
        if np.linalg.cond(normal) > 1e12:
            raise ValueError("dvl_altitude_var_m2: footprints do not span a plane")
        sigma2 = self.dvl_range_noise_m**2 * float(np.mean(down**2))
        return sigma2 * float(np.linalg.inv(normal)[0, 0])

    def altimeter_altitude_var_m2(self, range_m: float, vertical_per_range: float = 1.0) -> float:
        """Variance (m^2) of an altitude derived as ``range_m * vertical_per_range`` from one
        altimeter slant range ``range_m`` (m)."""
        sigma = self.altimeter_noise_m + self.altimeter_noise_frac_range * float(range_m)
        return (sigma * float(vertical_per_range)) ** 2
