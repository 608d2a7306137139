"""IMU/AHRS sensor: attitude (AHRS or FOG heading), body rates and specific force."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from autonomy.frames import wrap_angle
from autonomy.messages import ImuMsg
from scenarios.config.nav_sensors import ImuConfig
from sim.sensors.base import Mount, SceneView, Sensor
from sim.sensors.noise import RandomWalkBias, white_noise
from sim.sensors.registry import register_sensor
from sim.dynamics.truth import VehicleTruth

GRAVITY_MPS2 = 9.81
GRAVITY_NED_MPS2 = np.array([0.0, 0.0, GRAVITY_MPS2])  # NED z is down


@register_sensor(ImuConfig)
class ImuSensor(Sensor[ImuMsg]):
    """Strapdown IMU + AHRS at the mount point, axes along the body's (FRD).

    Ideal values: the true roll/pitch/yaw, body rates, and the specific force at the mount
    ``R_nb^T (a_mount_ned - g_ned)`` (FRD, m/s^2; at rest and level [0, 0, -9.81]).
    Corruption:
        rpy   = rpy_true + b_att(t) + w_att,   b_att: per-run constant, heading random walk (FOG)
        rate  = omega + b_g + w_g
        accel = f + b_a + w_a
    Biases are drawn in :meth:`reset`; yaw is wrapped to (-pi, pi].

    Raises:
        ValueError: the mount is rotated w.r.t. the body (not modelled).
    """

    def __init__(self, cfg: ImuConfig, mount: Mount | ArrayLike, rng: np.random.Generator | None = None, *,
                 name: str | None = None) -> None:
        super().__init__(cfg, mount, rng, name=name)
        if not self.mount.is_aligned:
            raise ValueError(f"sensors.{self.name}: an IMU rotated w.r.t. the body is not modelled (mount_rpy_deg)")
        rp_noise = math.radians(cfg.roll_pitch_noise_deg)
        self._attitude_noise_rad = np.array([rp_noise, rp_noise, cfg.heading_noise_rad])
        # (3, 3) white-noise sigmas, rows: attitude (rad), rate (rad/s), specific force (m/s^2)
        self._white_sigma = np.array([self._attitude_noise_rad, np.full(3, math.radians(cfg.gyro_noise_dps)),
                                      np.full(3, cfg.accel_noise_mps2)])

    def reset(self, rng: np.random.Generator) -> None:
        super().reset(rng)
        cfg = self.cfg
        rp = math.radians(cfg.roll_pitch_bias_deg)
        self._attitude_bias = RandomWalkBias(
            rng, [rp, rp, cfg.heading_bias_rad], [0.0, 0.0, cfg.heading_random_walk_rad_per_sqrt_s]
        )
        self._gyro_bias_radps = white_noise(rng, np.full(3, math.radians(cfg.gyro_bias_dps)))
        self._accel_bias_mps2 = white_noise(rng, np.full(3, cfg.accel_bias_mps2))

    def ideal(self, truth: VehicleTruth, scene: SceneView) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        """(t_s, rpy_rad (3,), rate_body_radps (3,), specific force FRD (3,)), yaw unwrapped
        (the attitude and rate are the truth's own arrays: :meth:`exact` and :meth:`corrupt`
        build new ones)."""
        # R_nb^T g_ned = g * (third row of R_nb): g_ned is along NED z
        specific_force = truth.point_accel_body(self.mount.pos_body_m) - GRAVITY_MPS2 * truth.R_nb[2]
        return truth.t_s, truth.rpy_rad, truth.nu[3:], specific_force

    def exact(self, ideal: tuple[float, np.ndarray, np.ndarray, np.ndarray]) -> ImuMsg:
        t_s, rpy, rate, specific_force = ideal
        rpy = np.array(rpy, dtype=float)
        rpy[2] = wrap_angle(float(rpy[2]))
        return ImuMsg(t_s=t_s, rpy_rad=rpy, rate_body_radps=np.array(rate, dtype=float),
                      accel_body_mps2=specific_force)

    def corrupt(self, ideal: tuple[float, np.ndarray, np.ndarray, np.ndarray], truth: VehicleTruth) -> ImuMsg:
        t_s, rpy, rate, specific_force = ideal
        bias_rpy = self._attitude_bias.at(t_s)
        # one draw for the white noise of the three outputs: attitude, rate, specific force
        w_att, w_rate, w_acc = (self._rng.standard_normal(9).reshape(3, 3) * self._white_sigma).tolist()
        # true + bias + noise per component in Python floats (this runs at the IMU rate; the
        # same sums in the same order as the numpy expression rpy + bias_rpy + w_att)
        roll, pitch, yaw = [a + b + c for a, b, c in zip(rpy.tolist(), bias_rpy.tolist(), w_att)]
        rate = [a + b + c for a, b, c in zip(rate.tolist(), self._gyro_bias_radps.tolist(), w_rate)]
        accel = [a + b + c for a, b, c in zip(specific_force.tolist(), self._accel_bias_mps2.tolist(), w_acc)]
        return ImuMsg(t_s=t_s, rpy_rad=np.array([roll, pitch, wrap_angle(yaw)]), rate_body_radps=np.array(rate),
                      accel_body_mps2=np.array(accel))
