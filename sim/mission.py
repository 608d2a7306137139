"""The closed-loop mission: physics, sensors and autonomy at their own rates.

One :class:`Mission` owns the MuJoCo world, the vehicle, the sensors and the onboard
stack. :meth:`Mission.step` advances one autonomy period (physics substeps, sensors due
in that time, delivery of latent messages, one autonomy tick). Gym environments reuse
this stepping API and may override guidance with their own setpoints.

Perception runs on every FLS frame when it is delivered: ATR -> geolocalisation -> PMHA.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from autonomy.control.allocation import ThrustAllocator
from autonomy.control.autopilot import Autopilot
from autonomy.control.setpoint import Setpoint
from autonomy.guidance.mission import MissionFsm
from autonomy.guidance.survey import SurveyGuidance
from autonomy.messages import AltimeterMsg, DepthMsg, DvlMsg, GpsMsg, ImuMsg, NavEstimate
from autonomy.navigation import NavigationFilter
from scenarios.schema import Scenario
from sim.current import OceanCurrent
from sim.perception import Perception
from sim.records import FlsEvent, MissionObserver, StepRecord
from sim.rng import component_rng
from sim.scheduler import SensorScheduler
from sim.sensors.fls import FlsSensor
from sim.sensors.nav_noise import nav_noise_model
from sim.sensors.nav_suite import build_nav_sensors
from sim.sensors.raycast import MujocoRayCaster
from sim.truth import VehicleTruth
from sim.vehicle import VehicleDynamics
from sim.vehicle_params import load_vehicle_params
from sim.world import World, build_world

NAV_SOURCES = ("estimate", "truth")


@dataclass(frozen=True)
class MissionSummary:
    sim_time_s: float
    wall_time_s: float
    finished: bool
    aborted: bool
    abort_reason: str


class Mission:
    """A closed-loop survey mission built from one scenario.

    Args:
        scenario: the validated scenario.
        nav_source: pose used for target geolocalisation: ``estimate`` (navigation filter)
            or ``truth`` (true vehicle pose, as paper 000's simulated evaluation).
        observers: readers of the step records (logs, plots, recordings).
        perception: run ATR/localisation/world model on FLS frames (False: FLS frames are
            still rendered at their rate when the sensor is enabled, but not processed).
    """

    def __init__(
        self,
        scenario: Scenario,
        *,
        nav_source: str = "estimate",
        observers: Sequence[MissionObserver] = (),
        perception: bool = True,
    ) -> None:
        if nav_source not in NAV_SOURCES:
            raise ValueError(f"nav_source must be one of {NAV_SOURCES}, got {nav_source!r}")
        self.scenario = scenario
        self.nav_source = nav_source
        self.observers = list(observers)
        self.params = load_vehicle_params(scenario.vehicle)
        self.world: World = build_world(scenario)
        self.model, self.data = self.world.model, self.world.data
        self.dt_s = float(self.model.opt.timestep)
        auto_cfg = scenario.autonomy
        self.substeps = max(int(round(scenario.physics.rate_hz / auto_cfg.rate_hz)), 1)
        self.autonomy_dt_s = self.substeps * self.dt_s
        self.caster = MujocoRayCaster(self.model, self.data, self.world.geom_object_id,
                                      self.world.geom_reflectivity, self.world.vehicle_body_id)
        self.vehicle_envelope_m = tuple(self.params.envelope_m)
        self.perception_enabled = perception
        self._build_components(scenario.seed)

    # -- construction ----------------------------------------------------------------
    def _mount(self, site: str) -> NDArray[np.float64]:
        return self.world.site_pos_body(site)

    def _build_components(self, seed: int) -> None:
        scn = self.scenario
        self.seed = int(seed)
        self.current = OceanCurrent(scn.world.current, component_rng(seed, "current"))
        self.vehicle = VehicleDynamics(self.model, self.data, self.params, self.current,
                                       component_rng(seed, "vehicle"))
        mounts = {name: self._mount(name) for name in ("imu", "dvl", "depth", "altimeter", "gps")}
        self.nav_sensors = build_nav_sensors(scn.sensors, mounts, seed)
        fls_cfg = scn.sensors.fls
        self.fls = (
            FlsSensor(fls_cfg, self._mount("fls"), np.deg2rad([0.0, fls_cfg.tilt_deg, 0.0]),
                      component_rng(seed, "fls"))
            if fls_cfg.enabled else None
        )
        self.scheduler = SensorScheduler(eps_s=0.25 * self.dt_s)
        for name, sensor in self.nav_sensors.items():
            self.scheduler.add(name, sensor.rate_hz, sensor.latency_s)
        if self.fls is not None:
            self.scheduler.add("fls", self.fls.rate_hz, self.fls.latency_s)

        auto = scn.autonomy
        survey = auto.guidance.survey
        self._nav_noise = nav_noise_model(scn.sensors.imu, scn.sensors.dvl, scn.sensors.depth, scn.sensors.gps)
        self._mounts = mounts
        self.nav_filter = self._make_nav_filter()
        swath = self.fls.swath_width_m(survey.altitude_m) if self.fls is not None else None
        self.guidance = SurveyGuidance.from_config(survey, auto.guidance.los, swath_width_m=swath)
        self.waypoints_ne = np.asarray(self.guidance.plan.waypoints_ne_m)
        self.fsm = MissionFsm(auto.guidance.mission, self.guidance)
        self.autopilot = Autopilot(auto.control)
        self.allocator = ThrustAllocator.from_layout(self.params.layout)
        self.perception = (
            Perception(scn, self.fls, self.world.seabed, self.waypoints_ne, nav_source=self.nav_source)
            if (self.fls is not None and self.perception_enabled) else None
        )

    def _make_nav_filter(self) -> NavigationFilter:
        scn = self.scenario
        return NavigationFilter(scn.autonomy.navigation, np.asarray(scn.vehicle.initial_pos_ned, dtype=float),
                                float(np.deg2rad(scn.vehicle.initial_rpy_deg[2])), self._nav_noise, mounts=self._mounts)

    # -- stepping API ----------------------------------------------------------------
    def reset(self, seed: int | None = None) -> StepRecord:
        """Restart the mission; a given ``seed`` reseeds every component (same seed, same run)."""
        if seed is not None:
            self._build_components(int(seed))
        scn = self.scenario
        mujoco.mj_resetData(self.model, self.data)
        init_pos = np.asarray(scn.vehicle.initial_pos_ned, dtype=float)
        init_rpy = np.deg2rad(scn.vehicle.initial_rpy_deg)
        self.vehicle.reset(init_pos, init_rpy)
        mujoco.mj_forward(self.model, self.data)
        self.t_s = 0.0
        self.thruster_cmd = np.zeros(self.params.n_thrusters)
        self.wrench_body = np.zeros(6)
        self.scheduler.reset(0.0)
        self.nav_filter = self._make_nav_filter()
        self.guidance.start(init_pos[:2], float(init_rpy[2]))
        self.fsm.reset()
        self.autopilot.reset()
        if self.perception is not None:
            self.perception.reset()
        self.last_dvl_lock = True
        self._setpoint: Setpoint | None = None
        self._wall_start = time.perf_counter()
        self._wall_s = 0.0
        self.n_fls_frames = 0
        for obs in self.observers:
            obs.on_start(self)
        self._truth = self.vehicle.truth(self.t_s)
        return self._record(self._truth, self.nav_filter.estimate(), "idle")

    @property
    def done(self) -> bool:
        return self.fsm.done or self.t_s >= self.scenario.duration_s - 1e-9

    def step(self, setpoint: Setpoint | None = None) -> StepRecord:
        """Advance one autonomy period. ``setpoint`` overrides guidance (gym envs)."""
        truth = self._truth
        for _ in range(self.substeps):
            self.vehicle.step_inputs(self.thruster_cmd, self.dt_s)
            mujoco.mj_step(self.model, self.data)
            self.t_s += self.dt_s
            self.current.step(self.dt_s)
            due = self.scheduler.due(self.t_s)
            if due:
                truth = self.vehicle.truth(self.t_s)
                for name in due:
                    self._fire(name, truth)
        if truth.t_s != self.t_s:  # not already taken for a sensor on the last substep
            truth = self.vehicle.truth(self.t_s)
        self._truth = truth
        for name, msg in self.scheduler.pop_ready(self.t_s):
            self._deliver(name, msg)
        self.nav_filter.predict(self.t_s)
        nav = self.nav_filter.estimate()
        sp = setpoint if setpoint is not None else self.fsm.update(self.t_s, nav, self.last_dvl_lock)
        self._setpoint = sp
        self.wrench_body = np.zeros(6) if sp is None else self.autopilot.update(nav, sp, self.autonomy_dt_s)
        self.thruster_cmd = self.allocator.allocate(self.wrench_body)
        rec = self._record(truth, nav, self.fsm.mode)
        self._wall_s = time.perf_counter() - self._wall_start
        return rec

    def run(self, progress: bool = True) -> MissionSummary:
        """Run until the mission ends or the scenario's duration is reached."""
        from tqdm import tqdm

        if not hasattr(self, "t_s"):
            self.reset()
        total = self.scenario.duration_s
        with tqdm(total=round(total), unit="sim s", disable=not progress, desc=self.scenario.name, mininterval=1.0,
                  bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} sim s [{elapsed}<{remaining}, {rate_fmt}]") as bar:
            last = 0.0
            while not self.done:
                self.step()
                if self.t_s - last >= 1.0:
                    bar.update(self.t_s - last)
                    bar.set_postfix_str(self.fsm.mode)
                    last = self.t_s
        for obs in self.observers:
            obs.on_end(self)
        return self.summary()

    def summary(self) -> MissionSummary:
        return MissionSummary(self.t_s, self._wall_s, self.fsm.done and not self.fsm.aborted,
                              self.fsm.aborted, self.fsm.abort_reason or "")

    # -- internals -------------------------------------------------------------------
    def _fire(self, name: str, truth: VehicleTruth) -> None:
        if name == "fls":
            render = self.fls.render(truth.t_s, truth.point_ned(self.fls.mount_pos_body_m), truth.R_nb,
                                     self.caster, self.world.objects)
            self.scheduler.push(name, truth.t_s, render)
            return
        msg = self.nav_sensors[name].measure(truth, caster=self.caster)
        self.scheduler.push(name, truth.t_s, msg)

    def _deliver(self, name: str, msg) -> None:
        nf = self.nav_filter
        if isinstance(msg, ImuMsg):
            nf.on_imu(msg)
        elif isinstance(msg, DvlMsg):
            self.last_dvl_lock = bool(msg.valid)
            nf.on_dvl(msg)
        elif isinstance(msg, DepthMsg):
            nf.on_depth(msg)
        elif isinstance(msg, AltimeterMsg):
            nf.on_altimeter(msg)
        elif isinstance(msg, GpsMsg):
            nf.on_gps(msg)
        elif name == "fls":
            self.n_fls_frames += 1
            event = FlsEvent(t_s=msg.frame.t_s, render=msg)
            if self.perception is not None:
                nav = nf.estimate()
                self.perception.process(event, nav)
            for obs in self.observers:
                obs.on_fls(event)

    def _record(self, truth: VehicleTruth, nav: NavEstimate, mode: str) -> StepRecord:
        sp = self._setpoint if getattr(self, "_setpoint", None) is not None else None
        nan = math.nan
        rec = StepRecord(
            t_s=self.t_s, truth=truth, nav=nav,
            setpoint_speed_mps=sp.speed_mps if sp else nan,
            setpoint_heading_rad=sp.heading_rad if sp else nan,
            setpoint_altitude_m=(sp.altitude_m if sp and sp.altitude_m is not None else nan),
            setpoint_depth_m=(sp.depth_m if sp and sp.depth_m is not None else nan),
            wrench_body=self.wrench_body.copy(), thruster_cmd=self.thruster_cmd.copy(), mode=mode,
        )
        for obs in self.observers:
            obs.on_step(rec)
        return rec

