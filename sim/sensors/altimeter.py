"""Single-beam altimeter (echo sounder) looking along body +z."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from autonomy.messages import AltimeterMsg
from scenarios.config.nav_sensors import AltimeterConfig
from sim.sensors.noise import dropped
from sim.sensors.base import HullSensor
from sim.sensors.raycast import RayCaster
from sim.truth import VehicleTruth

_BEAM_BODY = np.array([[0.0, 0.0, 1.0]])


class AltimeterSensor(HullSensor):
    """Range (m) along the body-down beam from ``mount_pos_body_m`` to the first surface hit.

    ``altitude_m`` is that slant range; it equals the altitude when the vehicle is level.
    Invalid (NaN) below ``min_range_m``, beyond ``max_range_m`` or on a dropout.
    Noise sigma is ``noise_m + noise_frac_range * range``.
    """

    name = "altimeter"

    def __init__(self, cfg: AltimeterConfig, mount_pos_body_m: ArrayLike, rng: np.random.Generator):
        if cfg.min_range_m >= cfg.max_range_m:
            raise ValueError("sensors.altimeter: min_range_m must be below max_range_m")
        super().__init__(cfg, mount_pos_body_m, rng)

    def measure(self, truth: VehicleTruth, *, caster: RayCaster | None = None, noise: bool = True) -> AltimeterMsg:
        if caster is None:
            raise ValueError("AltimeterSensor.measure needs a RayCaster (caster=...)")
        origin = truth.point_ned(self.mount_pos_body_m)
        hits = caster.cast(origin, _BEAM_BODY @ truth.R_nb.T, self.cfg.max_range_m)
        range_m = float(hits.dist_m[0])
        invalid = AltimeterMsg(t_s=truth.t_s, altitude_m=float("nan"), valid=False)
        if not (self.cfg.min_range_m <= range_m <= self.cfg.max_range_m):
            return invalid
        if noise:
            if dropped(self._rng, self.cfg.dropout_prob):
                return invalid
            sigma = self.cfg.noise_m + self.cfg.noise_frac_range * range_m
            range_m += float(self._rng.standard_normal()) * sigma
        return AltimeterMsg(t_s=truth.t_s, altitude_m=range_m, valid=True)
