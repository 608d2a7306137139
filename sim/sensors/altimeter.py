"""Single-beam altimeter (echo sounder) looking along the sensor's +z (body down when aligned)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from autonomy.messages import AltimeterMsg
from scenarios.config.nav_sensors import AltimeterConfig
from sim.sensors.base import Mount, SceneView, Sensor
from sim.sensors.noise import dropped
from sim.sensors.registry import register_sensor
from sim.dynamics.truth import VehicleTruth


@register_sensor(AltimeterConfig)
class AltimeterSensor(Sensor[AltimeterMsg]):
    """Range (m) along the beam from the mount point to the first surface hit.

    ``altitude_m`` is that slant range; it equals the altitude when the vehicle is level.
    Invalid (NaN) below ``min_range_m`` or beyond ``max_range_m``; corruption: dropouts, then
    noise of sigma ``noise_m + noise_frac_range * range``.

    Raises:
        ValueError: ``min_range_m >= max_range_m``; ``measure`` without a caster.
    """

    def __init__(self, cfg: AltimeterConfig, mount: Mount | ArrayLike, rng: np.random.Generator | None = None, *,
                 name: str | None = None) -> None:
        if cfg.min_range_m >= cfg.max_range_m:
            raise ValueError("sensors.altimeter: min_range_m must be below max_range_m")
        super().__init__(cfg, mount, rng, name=name)
        down = np.array([[0.0, 0.0, 1.0]])
        self._beam_body = down if self.mount.is_aligned else down @ self.mount.R_bs.T

    def ideal(self, truth: VehicleTruth, scene: SceneView) -> AltimeterMsg:
        caster = scene.require_caster("AltimeterSensor")
        origin = truth.point_ned(self.mount.pos_body_m)
        hits = caster.cast(origin, self._beam_body @ truth.R_nb.T, self.cfg.max_range_m)
        range_m = float(hits.dist_m[0])
        if not (self.cfg.min_range_m <= range_m <= self.cfg.max_range_m):
            return self._invalid(truth.t_s)
        return AltimeterMsg(t_s=truth.t_s, altitude_m=range_m, valid=True)

    def corrupt(self, ideal: AltimeterMsg, truth: VehicleTruth) -> AltimeterMsg:
        if not ideal.valid:
            return ideal
        if dropped(self._rng, self.cfg.dropout_prob):
            return self._invalid(ideal.t_s)
        range_m = ideal.altitude_m
        sigma = self.cfg.noise_m + self.cfg.noise_frac_range * range_m
        range_m += float(self._rng.standard_normal()) * sigma
        return AltimeterMsg(t_s=ideal.t_s, altitude_m=range_m, valid=True)

    @staticmethod
    def _invalid(t_s: float) -> AltimeterMsg:
        return AltimeterMsg(t_s=t_s, altitude_m=float("nan"), valid=False)
