"""GPS receiver: horizontal fixes only with the antenna at the surface."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from autonomy.messages import GpsMsg
from scenarios.config.nav_sensors import GpsConfig
from sim.sensors.noise import dropped, white_noise
from sim.sensors.base import HullSensor
from sim.sensors.raycast import RayCaster
from sim.truth import VehicleTruth


class GpsSensor(HullSensor):
    """North/east of the antenna at ``mount_pos_body_m`` (FRD) in the mission NED frame.

    No fix (``valid=False``, NaN position) while the antenna is deeper than
    ``cfg.max_antenna_depth_m`` or on a random dropout.
    """

    name = "gps"

    def __init__(self, cfg: GpsConfig, mount_pos_body_m: ArrayLike, rng: np.random.Generator):
        super().__init__(cfg, mount_pos_body_m, rng)

    def measure(self, truth: VehicleTruth, *, caster: RayCaster | None = None, noise: bool = True) -> GpsMsg:
        antenna_ned = truth.point_ned(self.mount_pos_body_m)
        no_fix = GpsMsg(t_s=truth.t_s, pos_ne_m=np.full(2, np.nan), valid=False)
        if antenna_ned[2] > self.cfg.max_antenna_depth_m:
            return no_fix
        pos_ne = antenna_ned[:2].copy()
        if noise:
            if dropped(self._rng, self.cfg.dropout_prob):
                return no_fix
            pos_ne += white_noise(self._rng, np.full(2, self.cfg.noise_m))
        return GpsMsg(t_s=truth.t_s, pos_ne_m=pos_ne, valid=True)
