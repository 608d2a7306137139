"""Building a mission's sensors and core onboard stack from a scenario (apart from running it).

:func:`build_mission_parts` makes the core the loop in :mod:`sim.mission.loop` ties together,
for one root seed: the sensors named in the scenario's sensor table (each from the registry,
mounted from its config, with its own ``component_rng(seed, name)``), their scheduler, and
the onboard stack every mission has (navigation filter factory, guidance, mission state
machine, autopilots, thrust allocation) and the choice of the forward-looking sonar whose
frames are processed (``autonomy.atr.sonar_sensor``, by default the first enabled one; the
tracker's sonar when tracking). What a study adds (perception, tracking, the sea trial, ...)
is built by its feature (:mod:`sim.features`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.control.allocation import ThrustAllocator
from autonomy.control.autopilot import Autopilot
from autonomy.guidance.inspection import InspectionGuidance
from autonomy.guidance.mission import MissionFsm
from autonomy.guidance.survey import SurveyGuidance, plan_from_config
from autonomy.navigation import NavigationFilter, NavNoiseModel
from scenarios.schema import Scenario
from scenarios.sensor_links import atr_sonar_name
from sim.scene.physics import Physics
from sim.events.scheduler import SensorScheduler
from sim.sensors.base import Sensor
from sim.sensors.nav_noise import nav_noise_model
from sim.sensors.registry import build_sensors

NAV_SOURCES = ("estimate", "truth")
#: Sensor kinds whose mounts the navigation filter takes (first sensor of each kind).
NAV_MOUNT_KINDS = ("dvl", "depth", "gps", "usbl", "altimeter")
PERCEPTION_SONAR_KIND = "fls"


@dataclass
class MissionParts:
    """Everything one run of a mission is made of, besides the physics.

    Attributes:
        seed: root seed the parts were built with.
        sensors: entry name -> sensor, in firing order.
        scheduler: fires the sensors at their rates and delivers after their latencies.
        nav_noise: the navigation filter's sensor noise model.
        nav_mounts: sensor kind -> (3,) FRD mount of the first sensor of that kind, m.
        guidance, fsm, autopilot, allocator: the onboard guidance and control (the guidance is
            an :class:`autonomy.guidance.inspection.InspectionGuidance` when
            ``autonomy.guidance.inspection.enabled``).
        waypoints_ne: (k, 2) survey plan, m (the coverage pass when inspecting).
        region_waypoints_ne: (k, 2) the lawnmower of the survey config, m: the world model's
            surveyed region is its bounding box (the same with or without inspection).
        sonar: the sonar whose frames are processed (``autonomy.atr.sonar_sensor``, default the
            first enabled fls entry; the tracker's ``autonomy.tracking.sonar_sensor`` when
            tracking; None: no forward-looking sonar). Other fls entries are rendered, not processed.
        usbl_beacon_pos_ned: (3,) known beacon of the first USBL aimed at ``beacon`` (or None).
    """

    seed: int
    sensors: dict[str, Sensor]
    scheduler: SensorScheduler
    nav_noise: NavNoiseModel
    nav_mounts: dict[str, NDArray[np.float64]]
    guidance: SurveyGuidance | InspectionGuidance
    fsm: MissionFsm
    autopilot: Autopilot
    allocator: ThrustAllocator
    waypoints_ne: NDArray[np.float64]
    sonar: Sensor | None
    usbl_beacon_pos_ned: NDArray[np.float64] | None = None
    region_waypoints_ne: NDArray[np.float64] | None = None

    def make_nav_filter(self, scenario: Scenario) -> NavigationFilter:
        """A fresh navigation filter at the scenario's start pose."""
        return NavigationFilter(scenario.autonomy.navigation, np.asarray(scenario.vehicle.initial_pos_ned, dtype=float),
                                float(np.deg2rad(scenario.vehicle.initial_rpy_deg[2])), self.nav_noise,
                                mounts=self.nav_mounts, usbl_beacon_pos_ned=self.usbl_beacon_pos_ned)


def build_mission_parts(scenario: Scenario, physics: Physics, seed: int) -> MissionParts:
    """Sensors, scheduler and core onboard stack of ``scenario`` for root ``seed``.

    Args:
        scenario: the validated scenario.
        physics: the world the sensors are mounted in (hull sites, seabed).
        seed: root seed.

    Raises:
        ValueError: a sensor's mount site is not on the hull; the tracker's sensors are
            missing or of the wrong kind; buddy guidance without tracking.
    """
    sensors = build_sensors(scenario.sensors.enabled(), physics.site_pos_body, seed)
    scheduler = SensorScheduler(eps_s=1e-6 * physics.dt_s)  # exact times: only rounding absorbed
    for name, sensor in sensors.items():
        scheduler.add(name, sensor.rate_hz, sensor.latency_s)

    first: dict[str, Sensor] = {}
    for sensor in sensors.values():
        first.setdefault(sensor.kind, sensor)
    nav_mounts = {kind: first[kind].mount_pos_body_m for kind in NAV_MOUNT_KINDS if kind in first}
    cfg_of = scenario.sensors.first_of_kind
    nav_noise = nav_noise_model(cfg_of("imu"), cfg_of("dvl"), cfg_of("depth"), cfg_of("gps"),
                                altimeter=cfg_of("altimeter"))

    auto = scenario.autonomy
    survey = auto.guidance.survey
    atr_sonar = atr_sonar_name(scenario)
    sonar = sensors.get(atr_sonar) if atr_sonar is not None else None
    swath = sonar.swath_width_m(survey.altitude_m) if sonar is not None else None
    inspection = auto.guidance.inspection
    if inspection.enabled:
        if sonar is None:  # the scenario's validation refuses this; a hand-built Scenario may not have been
            raise ValueError("autonomy.guidance.inspection needs a forward-looking sonar whose frames are processed")
        loc = auto.localization
        guidance = InspectionGuidance.from_config(
            survey, inspection, auto.guidance.los, swath_width_m=swath, fov_rad=sonar.geometry.fov_rad,
            range_sigma_m=loc.range_sigma_m, azimuth_sigma_rad=loc.azimuth_sigma_rad + loc.attitude_sigma_rad,
            altitude_sigma_m=loc.altitude_sigma_m, tilt_rad=sonar.tilt_down_rad,
            vertical_beam_rad=sonar.geometry.vertical_beamwidth_rad)
        region = np.asarray(plan_from_config(survey, swath).waypoints_ne_m)
    else:
        guidance = SurveyGuidance.from_config(survey, auto.guidance.los, swath_width_m=swath)
        region = None
    waypoints_ne = np.asarray(guidance.plan.waypoints_ne_m)
    fsm = MissionFsm(auto.guidance.mission, guidance)
    if auto.tracking.enabled:  # the tracker reads its own sonar (checked here: the core picks the sonar)
        usbl = sensors.get(auto.tracking.usbl_sensor)
        fls = sensors.get(auto.tracking.sonar_sensor)
        if fls is None or fls.kind != PERCEPTION_SONAR_KIND or usbl is None or usbl.kind != "usbl":
            raise ValueError(f"autonomy.tracking needs sensors {auto.tracking.sonar_sensor!r} (fls) and "
                             f"{auto.tracking.usbl_sensor!r} (usbl)")
        sonar = fls
    if auto.guidance.buddy.enabled and not auto.tracking.enabled:
        raise ValueError("autonomy.guidance.buddy needs autonomy.tracking.enabled")
    beacon = next((np.asarray(s.cfg.beacon_pos_ned, dtype=float) for s in sensors.values()
                   if s.kind == "usbl" and s.cfg.transponder == "beacon"), None)
    return MissionParts(
        seed=int(seed), sensors=sensors, scheduler=scheduler, nav_noise=nav_noise, nav_mounts=nav_mounts,
        guidance=guidance, fsm=fsm, autopilot=Autopilot(auto.control),
        allocator=ThrustAllocator.from_layout(physics.params.layout), waypoints_ne=waypoints_ne, sonar=sonar,
        usbl_beacon_pos_ned=beacon, region_waypoints_ne=waypoints_ne if region is None else region,
    )
