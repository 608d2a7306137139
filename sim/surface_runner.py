"""The sim side of a surface vessel's autonomy: its GNSS and compass fire at their rates,
its onboard :class:`autonomy.surface.buoy.SurfaceAutonomy` ticks at its rate, and the
commands go to the physics (:meth:`sim.physics.Physics.set_command`).

:class:`SurfaceVehicleRunner` is what the mission loop ticks once per autonomy period for
each extra vehicle of the scenario (and what the tests drive directly).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from autonomy.messages import GpsMsg, ImuMsg
from autonomy.surface.buoy import SurfaceAutonomy
from scenarios.config.vehicle import SurfaceVehicleConfig
from sim.physics import Physics
from sim.rng import component_rng
from sim.sensors.base import Mount, Sensor
from sim.sensors.registry import build_sensor

#: Entry name of each sensor of an extra vehicle -> the preset's mount it sits on.
SENSOR_MOUNTS = {"gnss": "gps", "compass": "imu"}


class SurfaceVehicleRunner:
    """One extra vehicle's sensors and autonomy, bound to a :class:`Physics`.

    Args:
        physics: the physics holding vehicle ``name``.
        name: the vehicle's key in ``scenario.vehicles``.
        cfg: its config.
        seed: root seed; the sensors draw from ``component_rng(seed, "vehicles.<name>.<sensor>")``.

    Attributes:
        sensors: ``gnss`` (a ``gps`` sensor) and ``compass`` (an ``imu`` sensor, AHRS heading).
        autonomy: the onboard autonomy.
        n_gnss_fixes: GNSS messages handed to the autonomy since :meth:`reset`.
    """

    def __init__(self, physics: Physics, name: str, cfg: SurfaceVehicleConfig, seed: int) -> None:
        self.physics, self.name, self.cfg = physics, name, cfg
        params = physics.extras[name].params
        self.sensors: dict[str, Sensor] = {}
        for entry, mount_name in SENSOR_MOUNTS.items():
            scfg = getattr(cfg, entry)
            if not scfg.enabled:
                continue
            mount = Mount.from_config(entry, scfg, lambda _site, m=mount_name: params.sensors[m].pos_body_m)
            self.sensors[entry] = build_sensor(f"vehicles.{name}.{entry}", scfg, mount,
                                               component_rng(seed, f"vehicles.{name}.{entry}"))
        station = cfg.initial_pos_ne_m if cfg.station_ne_m is None else cfg.station_ne_m
        self.autonomy = SurfaceAutonomy(cfg.autonomy, params.layout, behaviour=cfg.behaviour,
                                        station_ne_m=station, offset_ne_m=cfg.offset_m,
                                        offset_frame=cfg.offset_frame)
        self.reset()

    def reset(self) -> None:
        """Clocks to 0 (call after :meth:`Physics.reset`)."""
        self.autonomy.reset()
        self._next_s = {entry: 0.0 for entry in self.sensors}
        self._next_tick_s = 0.0
        self._gnss: list[GpsMsg] = []
        self._compass: ImuMsg | None = None
        self.n_gnss_fixes = 0

    def tick(self, target_pos_ned: ArrayLike | None = None) -> None:
        """At the physics' present time: fire the sensors that are due and, when the
        autonomy is due, run it with what arrived (``target_pos_ned``: the followed
        vehicle's latest position, NED m, or None) and hold its thruster commands."""
        t = self.physics.t_s
        eps = 1e-9
        truth = None
        for entry, sensor in self.sensors.items():
            if t + eps >= self._next_s[entry]:
                truth = self.physics.truth(self.name) if truth is None else truth
                msg = sensor.measure(truth)
                if entry == "gnss":
                    self._gnss.append(msg)
                else:
                    self._compass = msg
                period = 1.0 / sensor.rate_hz
                self._next_s[entry] += period * max(1, math.floor((t + eps - self._next_s[entry]) / period) + 1)
        if t + eps < self._next_tick_s:
            return
        period = 1.0 / self.cfg.autonomy.rate_hz
        self._next_tick_s += period * max(1, math.floor((t + eps - self._next_tick_s) / period) + 1)
        cmd = self.autonomy.update(t, self._gnss, self._compass, target_pos_ned)
        self.n_gnss_fixes += len(self._gnss)
        self._gnss = []
        self.physics.set_command(self.name, np.asarray(cmd, dtype=float))
