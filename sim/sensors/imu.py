"""IMU/AHRS sensor: attitude (AHRS or FOG heading), body rates and specific force."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from autonomy.frames import wrap_angle
from autonomy.messages import ImuMsg
from scenarios.config.nav_sensors import ImuConfig
from sim.sensors.noise import RandomWalkBias, white_noise
from sim.sensors.base import HullSensor
from sim.sensors.raycast import RayCaster
from sim.truth import VehicleTruth

GRAVITY_MPS2 = 9.81
GRAVITY_NED_MPS2 = np.array([0.0, 0.0, GRAVITY_MPS2])  # NED z is down


def _cross(a, b):
    """3-vector cross product (np.cross is slow for single vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


class ImuSensor(HullSensor):
    """Strapdown IMU + AHRS at ``mount_pos_body_m`` (FRD, m).

    Measurement model (``noise=True``):
        rpy   = rpy_true + b_att(t) + w_att,   b_att: per-run constant, heading random walk (FOG)
        rate  = omega + b_g + w_g
        accel = R_nb^T (a_mount_ned - g_ned) + b_a + w_a   (specific force, FRD)
    At rest and level ``accel`` reads [0, 0, -9.81].
    """

    name = "imu"

    def __init__(self, cfg: ImuConfig, mount_pos_body_m: ArrayLike, rng: np.random.Generator):
        super().__init__(cfg, mount_pos_body_m, rng)
        rp = math.radians(cfg.roll_pitch_bias_deg)
        self._attitude_bias = RandomWalkBias(
            rng, [rp, rp, cfg.heading_bias_rad], [0.0, 0.0, cfg.heading_random_walk_rad_per_sqrt_s]
        )
        rp_noise = math.radians(cfg.roll_pitch_noise_deg)
        self._attitude_noise_rad = np.array([rp_noise, rp_noise, cfg.heading_noise_rad])
        self._gyro_bias_radps = white_noise(rng, np.full(3, math.radians(cfg.gyro_bias_dps)))
        self._accel_bias_mps2 = white_noise(rng, np.full(3, cfg.accel_bias_mps2))

    def measure(self, truth: VehicleTruth, *, caster: RayCaster | None = None, noise: bool = True) -> ImuMsg:
        v, omega = truth.nu[:3], truth.nu[3:]
        v_dot, omega_dot = truth.nu_dot[:3], truth.nu_dot[3:]
        r = self.mount_pos_body_m
        # inertial acceleration of the mount point, body frame (v is body velocity over ground)
        accel_body = v_dot + _cross(omega, v) + _cross(omega_dot, r) + _cross(omega, _cross(omega, r))
        specific_force = accel_body - truth.R_nb.T @ GRAVITY_NED_MPS2
        rpy = np.array(truth.rpy_rad, dtype=float)
        rate = np.array(omega, dtype=float)
        if noise:
            rpy = rpy + self._attitude_bias.at(truth.t_s) + white_noise(self._rng, self._attitude_noise_rad)
            rate = rate + self._gyro_bias_radps + white_noise(self._rng, np.full(3, math.radians(self.cfg.gyro_noise_dps)))
            specific_force = (
                specific_force + self._accel_bias_mps2 + white_noise(self._rng, np.full(3, self.cfg.accel_noise_mps2))
            )
        rpy[2] = float(wrap_angle(rpy[2]))
        return ImuMsg(t_s=truth.t_s, rpy_rad=rpy, rate_body_radps=rate, accel_body_mps2=specific_force)
