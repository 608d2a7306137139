"""USBL: range, bearing and elevation of a transponder, late by the acoustic travel time.

The head sits at the mount (FRD offset and roll/pitch/yaw of its frame); the transponder is
a fixed beacon or a scene object (its centroid at capture time, so a moving diver is fixed
where it is when interrogated). The message carries that capture time; the scheduler
delivers it :meth:`UsblSensor.latency_s` later (paper 004 section 3: USBL fixes are sparse
and delayed by acoustic propagation). Noise, multipath outliers and dropouts follow
:class:`scenarios.config.usbl.UsblConfig` and draw from the sensor's own stream.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.estimation.measurement import RangeBearingElevation
from autonomy.messages import UsblMsg
from scenarios.config.usbl import UsblConfig
from sim.sensors.base import SceneView, Sensor
from sim.sensors.noise import dropped
from sim.sensors.registry import register_sensor
from sim.dynamics.truth import VehicleTruth

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class UsblIdeal:
    """Exact fix: [range_m, bearing_rad, elevation_rad] (3,) in the head frame, or None out of range."""

    t_s: float
    rbe: FloatArray | None


@register_sensor(UsblConfig)
class UsblSensor(Sensor[UsblMsg]):
    """USBL head interrogating ``cfg.transponder``.

    Raises (from :meth:`measure`):
        ValueError: the transponder object is not in the scene.
    """

    cfg: UsblConfig
    fixed_latency = False  # latency_s adds the two-way travel time of the measured range
    _spherical = RangeBearingElevation()

    def transponder_ned(self, scene: SceneView) -> FloatArray:
        """(3,) NED position of the transponder at the scene's time, m.

        Raises:
            ValueError: no scene object of that name.
        """
        cfg = self.cfg
        if cfg.transponder == "beacon":
            return np.asarray(cfg.beacon_pos_ned, dtype=float)
        for obj in scene.objects:
            if obj.name == cfg.transponder:
                return np.asarray(obj.centroid_ned, dtype=float)
        raise ValueError(f"sensors.{self.name}: transponder {cfg.transponder!r} is not a scene object "
                         f"(known: {sorted(o.name for o in scene.objects)})")

    def ideal(self, truth: VehicleTruth, scene: SceneView) -> UsblIdeal:
        head_ned = truth.point_ned(self.mount.pos_body_m)
        d_head = self.mount.R_bs.T @ (truth.R_nb.T @ (self.transponder_ned(scene) - head_ned))
        rbe = self._spherical.function(d_head)
        return UsblIdeal(truth.t_s, rbe if rbe[0] <= self.cfg.max_range_m else None)

    def exact(self, ideal: UsblIdeal) -> UsblMsg:
        if ideal.rbe is None:
            return self._no_fix(ideal.t_s)
        r, b, e = (float(v) for v in ideal.rbe)
        return UsblMsg(ideal.t_s, r, b, e, self.cfg.transponder, True)

    def corrupt(self, ideal: UsblIdeal, truth: VehicleTruth) -> UsblMsg:
        cfg, rng = self.cfg, self._rng
        if ideal.rbe is None or dropped(rng, cfg.dropout_prob):
            return self._no_fix(ideal.t_s)
        r, b, e = (float(v) for v in ideal.rbe)
        sig_r = cfg.range_sigma_at(r)
        sig_a = np.radians(cfg.angle_sigma_deg_at(r))
        n = rng.standard_normal(3)
        r_m, b_m, e_m = r + sig_r * n[0], b + sig_a * n[1], e + sig_a * n[2]
        if dropped(rng, cfg.outlier_prob):  # multipath: a longer path from another direction
            r_m += cfg.outlier_extra_range_m * rng.random()
            o = np.radians(cfg.outlier_angle_sigma_deg) * rng.standard_normal(2)
            b_m, e_m = b_m + o[0], e_m + o[1]
        b_m = float(np.angle(np.exp(1j * b_m)))
        e_m = float(np.clip(e_m, -0.5 * np.pi, 0.5 * np.pi))
        return UsblMsg(ideal.t_s, max(r_m, 0.0), b_m, e_m, cfg.transponder, True)

    def latency_s(self, msg: UsblMsg) -> float:
        """Processing delay + transponder turnaround + two-way travel time of the measured range, s."""
        cfg = self.cfg
        travel = 2.0 * msg.range_m / cfg.sound_speed_mps if msg.valid else 0.0
        return float(cfg.latency_s + cfg.turnaround_s + travel)

    def _no_fix(self, t_s: float) -> UsblMsg:
        nan = float("nan")
        return UsblMsg(t_s, nan, nan, nan, self.cfg.transponder, False)
