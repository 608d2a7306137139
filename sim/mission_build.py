"""Building a mission's sensors and onboard stack from a scenario (apart from running it).

:func:`build_mission_parts` makes everything the loop in :mod:`sim.mission` ties together,
for one root seed: the sensors named in the scenario's sensor table (each from the registry,
mounted from its config, with its own ``component_rng(seed, name)``), their scheduler, and
the onboard stack (navigation filter factory, guidance, mission state machine, autopilots,
thrust allocation and perception on the frames of one forward-looking sonar:
``autonomy.atr.sonar_sensor``, by default the first enabled one).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from autonomy.control.allocation import ThrustAllocator
from autonomy.control.autopilot import Autopilot
from autonomy.guidance.buddy import BuddyObserver
from autonomy.guidance.mission import MissionFsm
from autonomy.guidance.survey import SurveyGuidance
from autonomy.msis.localization import MsisLocalizer
from autonomy.navigation import NavigationFilter, NavNoiseModel
from scenarios.schema import Scenario
from scenarios.sensor_links import atr_sonar_name
from sim.perception import Perception
from sim.physics import Physics
from sim.rng import component_rng
from sim.scheduler import SensorScheduler
from sim.sensors.base import Sensor
from sim.sensors.nav_noise import nav_noise_model
from sim.sensors.registry import build_sensors

if TYPE_CHECKING:
    from autonomy.tracking.onboard import TrackingStack

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
        guidance, fsm, autopilot, allocator: the onboard guidance and control.
        waypoints_ne: (k, 2) survey plan, m.
        sonar: the sonar perception runs on (``autonomy.atr.sonar_sensor``, default the first
            enabled fls entry; the tracker's ``autonomy.tracking.sonar_sensor`` when tracking;
            None: no forward-looking sonar). Other fls entries are rendered, not processed.
        perception: ATR -> geolocalisation -> world model on ``sonar``'s frames (or None).
        processors: sensor name -> onboard processing of its messages ``(msg, nav) -> result``;
            a result the navigation filter handles (a position fix) is fused.
        usbl_beacon_pos_ned: (3,) known beacon of the first USBL aimed at ``beacon`` (or None).
        tracking: the target trackers on the USBL fixes and ``sonar``'s frames (or None;
            with tracking the survey perception is not built).
        buddy: the buddy-observer guidance following the tracked target (or None: the survey).
    """

    seed: int
    sensors: dict[str, Sensor]
    scheduler: SensorScheduler
    nav_noise: NavNoiseModel
    nav_mounts: dict[str, NDArray[np.float64]]
    guidance: SurveyGuidance
    fsm: MissionFsm
    autopilot: Autopilot
    allocator: ThrustAllocator
    waypoints_ne: NDArray[np.float64]
    sonar: Sensor | None
    perception: Perception | None
    processors: dict[str, Callable[[Any, Any], Any]] = field(default_factory=dict)
    usbl_beacon_pos_ned: NDArray[np.float64] | None = None
    tracking: TrackingStack | None = None
    buddy: BuddyObserver | None = None

    def make_nav_filter(self, scenario: Scenario) -> NavigationFilter:
        """A fresh navigation filter at the scenario's start pose."""
        return NavigationFilter(scenario.autonomy.navigation, np.asarray(scenario.vehicle.initial_pos_ned, dtype=float),
                                float(np.deg2rad(scenario.vehicle.initial_rpy_deg[2])), self.nav_noise,
                                mounts=self.nav_mounts, usbl_beacon_pos_ned=self.usbl_beacon_pos_ned)


class MsisPingProcessor:
    """Onboard processing of a scanning sonar's renders: the ping (never its truth) goes to
    the localiser, which may return a position fix."""

    def __init__(self, localizer: MsisLocalizer) -> None:
        self.localizer = localizer

    def __call__(self, render: Any, nav: Any) -> Any:
        return self.localizer.process(render.ping, nav)

    def reset(self) -> None:
        self.localizer.reset()


def build_mission_parts(scenario: Scenario, physics: Physics, seed: int, *, nav_source: str = "estimate",
                        perception: bool = True) -> MissionParts:
    """Sensors, scheduler and onboard stack of ``scenario`` for root ``seed``.

    Args:
        scenario: the validated scenario.
        physics: the world the sensors are mounted in (hull sites, seabed).
        seed: root seed.
        nav_source: pose used for geolocalisation, one of :data:`NAV_SOURCES`.
        perception: build perception for the ATR's sonar (:func:`scenarios.sensor_links.atr_sonar_name`).

    Raises:
        ValueError: unknown ``nav_source``; a sensor's mount site is not on the hull.
    """
    if nav_source not in NAV_SOURCES:
        raise ValueError(f"nav_source must be one of {NAV_SOURCES}, got {nav_source!r}")
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
    guidance = SurveyGuidance.from_config(survey, auto.guidance.los, swath_width_m=swath)
    waypoints_ne = np.asarray(guidance.plan.waypoints_ne_m)
    fsm = MissionFsm(auto.guidance.mission, guidance)
    tracking = None
    if auto.tracking.enabled:
        usbl = sensors.get(auto.tracking.usbl_sensor)
        fls = sensors.get(auto.tracking.sonar_sensor)
        if fls is None or fls.kind != PERCEPTION_SONAR_KIND or usbl is None or usbl.kind != "usbl":
            raise ValueError(f"autonomy.tracking needs sensors {auto.tracking.sonar_sensor!r} (fls) and "
                             f"{auto.tracking.usbl_sensor!r} (usbl)")
        sonar = fls
        from autonomy.tracking.onboard import TrackingStack  # scipy.stats: only missions that track

        tracking = TrackingStack(auto.tracking, auto.atr.classical, usbl_mount_body_m=usbl.mount.pos_body_m,
                                 usbl_mount_rpy_rad=usbl.mount.rpy_rad, sonar_mount_body_m=fls.mount.pos_body_m,
                                 sonar_mount_rpy_rad=fls.mount.rpy_rad)
    buddy = None
    if auto.guidance.buddy.enabled:
        if tracking is None:
            raise ValueError("autonomy.guidance.buddy needs autonomy.tracking.enabled")
        buddy = BuddyObserver(auto.guidance.buddy, float(np.deg2rad(scenario.vehicle.initial_rpy_deg[2])),
                              float(scenario.vehicle.initial_pos_ned[2]))
    beacon = next((np.asarray(s.cfg.beacon_pos_ned, dtype=float) for s in sensors.values()
                   if s.kind == "usbl" and s.cfg.transponder == "beacon"), None)
    perceive = (Perception(scenario, sonar, physics.world.seabed, waypoints_ne, nav_source=nav_source)
                if sonar is not None and perception and tracking is None else None)
    processors: dict[str, Callable[[Any, Any], Any]] = {}
    msis = first.get("msis")
    if msis is not None and auto.msis_localization.method != "none":
        localizer = MsisLocalizer(auto.msis_localization, component_rng(seed, f"{msis.name}_localizer"))
        processors[msis.name] = MsisPingProcessor(localizer)
    if scenario.mcm.mode == "full":
        from sim.mcm.full_mode import SssTileProcessor

        processors[scenario.mcm.sensor] = SssTileProcessor(scenario)
    return MissionParts(
        processors=processors,
        seed=int(seed), sensors=sensors, scheduler=scheduler, nav_noise=nav_noise, nav_mounts=nav_mounts,
        guidance=guidance, fsm=fsm, autopilot=Autopilot(auto.control),
        allocator=ThrustAllocator.from_layout(physics.params.layout), waypoints_ne=waypoints_ne, sonar=sonar,
        perception=perceive, usbl_beacon_pos_ned=beacon, tracking=tracking, buddy=buddy,
    )
