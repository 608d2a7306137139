"""The sim side of a surface vessel's autonomy: its GNSS and compass fire at their rates,
its onboard :class:`autonomy.surface.buoy.SurfaceAutonomy` ticks at its rate, and the
commands go to the physics (:meth:`sim.scene.physics.Physics.set_command`).

With a ``usbl`` head in its config, the vessel's USBL fixes the AUV's transponder (at the
AUV's body origin) at the USBL's rate; each fix reaches the vessel's computer after the
USBL's latency and becomes a position of the AUV in the mission frame
(:class:`autonomy.surface.usbl_fix.UsblFixer`, from the vessel's GNSS filter and compass):
a following vessel follows these fixes, not the AUV's true position, and they are queued in
:attr:`SurfaceVehicleRunner.auv_fixes` for the acoustic link.

:class:`SurfaceVehicleRunner` keeps no clock: it declares its periodic events
(:meth:`SurfaceVehicleRunner.periodic_events`: each sensor's firing and the autonomy tick, at
their rates) and whoever runs it orders them on a scheduler (:class:`sim.events.scheduler.SensorScheduler`;
in a mission, the loop's, at the autonomy ticks: :mod:`sim.features.sea_trial`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial

import numpy as np
from numpy.typing import ArrayLike

from dataclasses import dataclass

from autonomy.messages import GpsMsg, ImuMsg, UsblMsg
from autonomy.surface.buoy import SurfaceAutonomy
from autonomy.surface.usbl_fix import UsblFixer
from scenarios.config.vehicle import SurfaceVehicleConfig
from sim.scene.physics import Physics
from sim.rng import component_rng
from sim.sensors.base import Mount, SceneView, Sensor
from sim.sensors.registry import build_sensor
from sim.dynamics.truth import VehicleTruth

#: Entry name of each sensor of an extra vehicle -> the preset's mount it sits on.
SENSOR_MOUNTS = {"gnss": "gps", "compass": "imu", "usbl": "usbl"}


@dataclass(frozen=True, slots=True)
class _Transponder:
    """The AUV's transponder as the vessel's USBL sees it (a scene object named ``auv``)."""

    centroid_ned: np.ndarray
    id: int = -1
    name: str = "auv"
    class_name: str = "transponder"
    is_target: bool = False


@dataclass(frozen=True, slots=True)
class AuvFix:
    """The vessel's fix of the AUV: measurement time (s), position (3,) and covariance
    (3, 3) in the mission NED frame (m, m^2), and the vessel's own position (3,) then."""

    t_s: float
    pos_ned: np.ndarray
    cov_ned: np.ndarray
    vessel_pos_ned: np.ndarray


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
            if scfg is None or not scfg.enabled:
                continue
            mount = Mount.from_config(entry, scfg, lambda _site, m=mount_name: params.sensors[m].pos_body_m)
            self.sensors[entry] = build_sensor(f"vehicles.{name}.{entry}", scfg, mount,
                                               component_rng(seed, f"vehicles.{name}.{entry}"))
        station = cfg.initial_pos_ne_m if cfg.station_ne_m is None else cfg.station_ne_m
        self.usbl_fixer = None
        self._gnss_mount_body_m = (self.sensors["gnss"].mount.pos_body_m if "gnss" in self.sensors
                                   else np.zeros(3))
        usbl = self.sensors.get("usbl")
        if usbl is not None:
            ucfg, ccfg = cfg.usbl, cfg.compass
            self.usbl_fixer = UsblFixer(
                usbl.mount.pos_body_m, usbl.mount.rpy_rad, range_sigma_m=ucfg.range_sigma_m,
                range_sigma_frac=ucfg.range_sigma_frac, angle_sigma_rad=math.radians(ucfg.angle_sigma_deg),
                angle_sigma_rad_per_m=math.radians(ucfg.angle_sigma_deg_per_100m) / 100.0,
                heading_sigma_rad=math.radians(math.hypot(ccfg.ahrs_heading_noise_deg, ccfg.ahrs_heading_bias_deg)))
        self.autonomy = SurfaceAutonomy(cfg.autonomy, params.layout, behaviour=cfg.behaviour,
                                        station_ne_m=station, offset_ne_m=cfg.offset_m,
                                        offset_frame=cfg.offset_frame)
        self.reset()

    def reset(self) -> None:
        """A fresh autonomy and empty queues (call after :meth:`Physics.reset`)."""
        self.autonomy.reset()
        self._gnss: list[GpsMsg] = []
        self._compass: ImuMsg | None = None
        self._usbl_in_flight: list[tuple[float, UsblMsg]] = []
        self._last_gnss: GpsMsg | None = None
        self._new_fix: np.ndarray | None = None
        self.n_gnss_fixes = 0
        #: Fixes of the AUV not yet taken by the acoustic link (:meth:`take_auv_fixes`).
        self.auv_fixes: list[AuvFix] = []
        self.n_usbl_fixes = 0

    def take_auv_fixes(self) -> list[AuvFix]:
        """The AUV fixes made since the last call (oldest first)."""
        out, self.auv_fixes = self.auv_fixes, []
        return out

    def periodic_events(self) -> list[tuple[str, float, Callable[..., None]]]:
        """``(name, rate_hz, event)`` of each periodic event, in the order events of one time
        run: each sensor's firing (``event(auv_truth)``), then the autonomy tick
        (``event(auv_truth)``: with no USBL the vessel follows the AUV's true position).
        Names are ``vehicles.<name>.<entry>`` and ``vehicles.<name>.autonomy``. Rates may not
        exceed the mission's autonomy rate (the scenario is refused at load otherwise)."""
        events: list[tuple[str, float, Callable[..., None]]] = [
            (f"vehicles.{self.name}.{entry}", sensor.rate_hz, partial(self.fire_sensor, entry))
            for entry, sensor in self.sensors.items()]
        events.append((f"vehicles.{self.name}.autonomy", self.cfg.autonomy.rate_hz,
                       lambda auv_truth: self.autonomy_tick(None if auv_truth is None else auv_truth.pos_ned)))
        return events

    def fire_sensor(self, entry: str, auv_truth: VehicleTruth | None = None) -> None:
        """Fire sensor ``entry`` at the physics' present time (the USBL measures ``auv_truth``,
        the AUV's true state now; without it the USBL does not fire)."""
        t = self.physics.t_s
        sensor = self.sensors[entry]
        truth = self.physics.truth(self.name)
        if entry == "usbl":
            if auv_truth is not None:
                msg = sensor.measure(truth, SceneView(t, None, (_Transponder(auv_truth.pos_ned),)))
                self._usbl_in_flight.append((t + sensor.latency_s(msg), msg))
        elif entry == "gnss":
            gnss = sensor.measure(truth)
            self._gnss.append(gnss)
            if gnss.valid:
                self._last_gnss = gnss
        else:
            self._compass = sensor.measure(truth)

    def autonomy_tick(self, target_pos_ned: ArrayLike | None = None) -> None:
        """Run the autonomy at the physics' present time with what arrived and hold its
        thruster commands.

        Args:
            target_pos_ned: the followed vehicle's latest position, NED m, or None; used
                when the vessel has no USBL (with one it follows its own fixes of the AUV).
        """
        t = self.physics.t_s
        if self.usbl_fixer is not None:
            target_pos_ned = self._take_usbl(t)
        cmd = self.autonomy.update(t, self._gnss, self._compass, target_pos_ned)
        self.n_gnss_fixes += len(self._gnss)
        self._gnss = []
        self.physics.set_command(self.name, np.asarray(cmd, dtype=float))

    def _take_usbl(self, t_s: float) -> np.ndarray | None:
        """Turn the USBL messages delivered by ``t_s`` into AUV fixes; the newest fix
        position, or None when none is new.

        The vessel's position at a fix is its latest raw GNSS fix (antenna lever arm removed
        with the compass heading) moved to the USBL time with the GNSS filter's velocity, with
        the receiver's noise as its covariance: as a USBL positioning system combines the
        fix of the moment, so that the fixes' errors are independent from one fix to the
        next, as the AUV's filter assumes (the GNSS filter's estimate would hand it errors
        correlated over the filter's time constant). Needs a GNSS fix, a valid GNSS filter
        and a compass reading."""
        newest = None
        nav = self.autonomy.nav
        gnss_var = self.cfg.autonomy.navigation.gnss_noise_m ** 2
        while self._usbl_in_flight and self._usbl_in_flight[0][0] <= t_s + 1e-9:
            _, msg = self._usbl_in_flight.pop(0)
            gnss = self._last_gnss
            if not msg.valid or self._compass is None or gnss is None or not nav.valid(t_s):
                continue
            heading = float(self._compass.rpy_rad[2])
            c, s = math.cos(heading), math.sin(heading)
            lever = self._gnss_mount_body_m
            vessel = (np.asarray(gnss.pos_ne_m, dtype=float) - np.array([c * lever[0] - s * lever[1],
                                                                         s * lever[0] + c * lever[1]])
                      + nav.vel_ne_mps * (msg.t_s - gnss.t_s))
            pos, cov = self.usbl_fixer.fix((msg.range_m, msg.bearing_rad, msg.elevation_rad), msg.t_s, msg.t_s,
                                           vessel, np.zeros(2), gnss_var * np.eye(2), heading)
            self.auv_fixes.append(AuvFix(float(msg.t_s), pos, cov, np.array([vessel[0], vessel[1], 0.0])))
            self.n_usbl_fixes += 1
            newest = pos
        return newest
