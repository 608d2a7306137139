"""Pressure depth sensor."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from autonomy.messages import DepthMsg
from scenarios.config.nav_sensors import DepthConfig
from sim.sensors.base import HullSensor
from sim.sensors.raycast import RayCaster
from sim.truth import VehicleTruth


class DepthSensor(HullSensor):
    """Depth (m, down positive) of the sensor at ``mount_pos_body_m`` (FRD) plus white noise."""

    name = "depth"

    def __init__(self, cfg: DepthConfig, mount_pos_body_m: ArrayLike, rng: np.random.Generator):
        super().__init__(cfg, mount_pos_body_m, rng)

    def measure(self, truth: VehicleTruth, *, caster: RayCaster | None = None, noise: bool = True) -> DepthMsg:
        depth_m = float(truth.point_ned(self.mount_pos_body_m)[2])
        if noise:
            depth_m += float(self._rng.standard_normal()) * self.cfg.noise_m
        return DepthMsg(t_s=truth.t_s, depth_m=depth_m)
