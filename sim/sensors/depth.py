"""Pressure depth sensor."""

from __future__ import annotations

from autonomy.messages import DepthMsg
from scenarios.config.nav_sensors import DepthConfig
from sim.sensors.base import SceneView, Sensor
from sim.sensors.registry import register_sensor
from sim.dynamics.truth import VehicleTruth


@register_sensor(DepthConfig)
class DepthSensor(Sensor[DepthMsg]):
    """Depth (m, down positive) of the sensor's mount point; corruption: white noise of
    ``cfg.noise_m``."""

    def ideal(self, truth: VehicleTruth, scene: SceneView) -> DepthMsg:
        return DepthMsg(t_s=truth.t_s, depth_m=float(truth.point_ned(self.mount.pos_body_m)[2]))

    def corrupt(self, ideal: DepthMsg, truth: VehicleTruth) -> DepthMsg:
        depth_m = ideal.depth_m + float(self._rng.standard_normal()) * self.cfg.noise_m
        return DepthMsg(t_s=ideal.t_s, depth_m=depth_m)
