"""GPS receiver: horizontal fixes only outdoors, with the antenna at the surface."""

from __future__ import annotations

import numpy as np

from autonomy.messages import GpsMsg
from scenarios.config.nav_sensors import GpsConfig
from sim.sensors.base import SceneView, Sensor
from sim.sensors.noise import dropped, white_noise
from sim.sensors.registry import register_sensor
from sim.dynamics.truth import VehicleTruth


@register_sensor(GpsConfig)
class GpsSensor(Sensor[GpsMsg]):
    """North/east (m) of the antenna at the mount point, in the mission NED frame.

    A fix is valid (``valid=True``) only when both hold:

    - outdoors: the satellites are in view. An indoor scenario (``world.indoor: true``,
      a roofed pool or tank) has no GPS at all: scenario validation leaves it out of the
      default suite and refuses an enabled one, so this sensor never runs indoors;
    - surfaced: the antenna (the mount point) is no deeper than ``cfg.max_antenna_depth_m``
      (L-band signals do not pass through water).

    Otherwise no fix (``valid=False``, NaN position). Corruption: random dropouts
    (``cfg.dropout_prob``), then white noise of ``cfg.noise_m`` per horizontal axis.
    """

    def ideal(self, truth: VehicleTruth, scene: SceneView) -> GpsMsg:
        antenna_ned = truth.point_ned(self.mount.pos_body_m)
        if antenna_ned[2] > self.cfg.max_antenna_depth_m:
            return self._no_fix(truth.t_s)
        return GpsMsg(t_s=truth.t_s, pos_ne_m=antenna_ned[:2].copy(), valid=True)

    def corrupt(self, ideal: GpsMsg, truth: VehicleTruth) -> GpsMsg:
        if not ideal.valid:
            return ideal
        if dropped(self._rng, self.cfg.dropout_prob):
            return self._no_fix(ideal.t_s)
        pos_ne = ideal.pos_ne_m.copy()
        pos_ne += white_noise(self._rng, np.full(2, self.cfg.noise_m))
        return GpsMsg(t_s=ideal.t_s, pos_ne_m=pos_ne, valid=True)

    @staticmethod
    def _no_fix(t_s: float) -> GpsMsg:
        return GpsMsg(t_s=t_s, pos_ne_m=np.full(2, np.nan), valid=False)
