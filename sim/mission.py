"""The closed-loop mission: physics, sensors and autonomy at their own rates.

:class:`Mission` runs the loop; :class:`sim.physics.Physics` owns the world and
:func:`sim.mission_build.build_mission_parts` builds the sensors and the onboard stack.
:meth:`Mission.step` advances one autonomy period: physics substeps, the sensors due in
that time (each at its own time, the true state interpolated between the steps for a firing
between them; every sensor first fires at t = 0, in :meth:`Mission.reset`), delivery of the
messages whose latency has passed, one autonomy tick. Gym
environments reuse this stepping API and may override guidance with their own setpoints.

Delivery dispatches on the message's type (the navigation filter's handlers, the state
machine's bottom-lock flag) and on its source (perception runs on the frames of its sonar:
ATR -> geolocalisation -> world model; or, when the scenario tracks a target, the tracking
stack takes the USBL fixes and that sonar's frames, and the buddy observer may guide). Observers receive every delivered message and the
perception results by sensor name, and immutable start and end summaries.

With extra vehicles (``scenario.vehicles``) each one's sensors and autonomy tick every
period (:class:`sim.surface_runner.SurfaceVehicleRunner`); with ``comms.acoustic`` on, the
acoustic link (:class:`sim.comms.vehicle_link.VehicleLink`) carries each frame's detections
up to the surface world model and the surface vehicle's USBL fixes down to the AUV, whose
navigation filter fuses them at their measurement time
(:class:`autonomy.navigation.delayed.DelayedFixFilter`).
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import Any

import numpy as np

from autonomy.control.setpoint import Setpoint
from autonomy.messages import DvlMsg, NavEstimate, UsblMsg, WrenchCmdMsg
from autonomy.navigation.delayed import DelayedFixFilter
from scenarios.schema import Scenario
from sim.mission_build import NAV_SOURCES, MissionParts, build_mission_parts
from sim.physics import Physics
from sim.comms.vehicle_link import VehicleLink
from sim.records import MissionInfo, MissionObserver, MissionSummary, PerceptionResult, StepRecord
from sim.sensors.base import SceneView, Sensor
from sim.sonar_pipeline import FrameTicket, SonarPipeline
from sim.stage_timer import NULL_TIMER, StageTimer
from sim.surface_runner import SurfaceVehicleRunner
from sim.truth import VehicleTruth, interpolate_truth

__all__ = ["NAV_SOURCES", "Mission", "MissionSummary"]


class Mission:
    """A closed-loop survey mission built from one scenario.

    Args:
        scenario: the validated scenario.
        nav_source: pose used for target geolocalisation: ``estimate`` (navigation filter)
            or ``truth`` (true vehicle pose, as paper 000's simulated evaluation).
        observers: readers of the mission's outputs (logs, plots, recordings). The forward-looking
            sonars compute their objects' ground truth and instance masks only when one of the
            observers present at :meth:`reset` reads them (one without ``sonar_truth = False``;
            see :class:`sim.records.MissionObserver`); otherwise the frames' truth holds the
            sonar pose only (the images are the same bytes).
        perception: run ATR/localisation/world model on the sonar's frames (False: frames
            are still rendered at their rate when the sonar is enabled, but not processed).
        timer: a :class:`sim.stage_timer.StageTimer` to time the loop's stages (benchmarks);
            default: none.
        workers: processes the loop may use. 1: the serial loop. 2 or more: the sonar's frames
            and their ATR detection run in two worker processes (:mod:`sim.sonar_pipeline`) when
            nothing in the loop reads perception back (survey perception; not target tracking),
            with the serial loop's results bit for bit; observers get frames and perception
            results once ready, in order (frames only if an observer takes them: one without
            ``sonar_frames = False``). Call :meth:`close` when done (it ends the workers). The
            workers start with ``spawn``: a script that builds the mission needs the
            ``if __name__ == "__main__":`` guard.

    Raises:
        ValueError: unknown ``nav_source``; ``workers`` < 1; a sensor mount site missing on the hull.
        sim.sonar_pipeline.PipelineError: (from :meth:`reset`, :meth:`step`, :meth:`run`) a
            pipeline worker failed or ended, or the main script lacks the ``__main__`` guard.
    """

    def __init__(
        self,
        scenario: Scenario,
        *,
        nav_source: str = "estimate",
        observers: Sequence[MissionObserver] = (),
        perception: bool = True,
        timer: StageTimer | None = None,
        workers: int = 1,
    ) -> None:
        if nav_source not in NAV_SOURCES:
            raise ValueError(f"nav_source must be one of {NAV_SOURCES}, got {nav_source!r}")
        if int(workers) < 1:
            raise ValueError(f"workers must be >= 1, got {workers}")
        self.workers = int(workers)
        self._pipeline: SonarPipeline | None = None
        self.scenario = scenario
        self.nav_source = nav_source
        self.observers = list(observers)
        self.timer = timer if timer is not None else NULL_TIMER
        self.perception_enabled = perception
        self.physics = Physics(scenario)
        self.dt_s = self.physics.dt_s
        self.substeps = max(int(round(scenario.physics.rate_hz / scenario.autonomy.rate_hz)), 1)
        self.autonomy_dt_s = self.substeps * self.dt_s
        self._build(scenario.seed)

    def _build(self, seed: int) -> None:
        self.physics.reseed(seed)
        self.parts: MissionParts = build_mission_parts(self.scenario, self.physics, seed, nav_source=self.nav_source,
                                                       perception=self.perception_enabled)
        #: The extra vehicles' sensors and autonomy (``scenario.vehicles``), ticked each period.
        self.surface_vehicles: dict[str, SurfaceVehicleRunner] = {
            name: SurfaceVehicleRunner(self.physics, name, cfg, seed) for name, cfg in self.scenario.vehicles.items()}
        #: The acoustic link to the surface vehicle (None: ``comms.acoustic`` off), built by :meth:`reset`.
        self.link: VehicleLink | None = None

    # -- read-only views ---------------------------------------------------------------
    @property
    def seed(self) -> int:
        return self.parts.seed

    @property
    def world(self):
        return self.physics.world

    @property
    def t_s(self) -> float:
        return self.physics.t_s

    @property
    def sensors(self):
        return self.parts.sensors

    @property
    def fls(self):
        """The sonar perception runs on (None without one)."""
        return self.parts.sonar

    @property
    def pipelined(self) -> bool:
        """Whether the sonar and its perception run in worker processes (``workers`` > 1 and a
        mission that allows it: FLS perception, no tracker); known after :meth:`reset`."""
        return self._pipeline is not None

    @property
    def perception(self):
        """The perception chain (None without one); pipelined frames delivered so far are
        finished first."""
        self.flush()
        if self._pipeline is not None:
            self._pipeline.sync()
        return self.parts.perception

    @property
    def fsm(self):
        return self.parts.fsm

    @property
    def waypoints_ne(self) -> np.ndarray:
        return self.parts.waypoints_ne

    @property
    def n_fls_frames(self) -> int:
        """Frames delivered from the sensors of kind ``fls`` (all of them: see
        :attr:`fls_frames_by_sensor` for each, :attr:`fls` for the one perception reads)."""
        return sum(self.fls_frames_by_sensor.values())

    @property
    def fls_frames_by_sensor(self) -> dict[str, int]:
        """Sensor name -> frames delivered, for every forward-looking sonar of the mission
        (0 for one that has delivered none yet), in the scenario's order."""
        return {name: int(self._delivered.get(name, 0)) for name, s in self.parts.sensors.items() if s.kind == "fls"}

    def info(self) -> MissionInfo:
        """What observers may know of the built mission."""
        waypoints = np.array(self.parts.waypoints_ne, dtype=float)
        waypoints.setflags(write=False)
        return MissionInfo(
            scenario=self.scenario, seed=self.seed, nav_source=self.nav_source, seabed=self.world.seabed,
            objects=tuple(self.world.objects), waypoints_ne=waypoints,
            vehicle_envelope_m=tuple(float(x) for x in self.physics.params.envelope_m),
            sensors=MappingProxyType({n: s.kind for n, s in self.parts.sensors.items()}),
            sensor_mounts=MappingProxyType({n: s.mount for n, s in self.parts.sensors.items()}),
            vehicle_envelopes_m=MappingProxyType({n: tuple(float(x) for x in e.params.envelope_m)
                                                  for n, e in self.physics.extras.items()}),
            perception_sonar=self.parts.sonar.name if self.parts.sonar is not None else None,
        )

    # -- stepping API ----------------------------------------------------------------
    def reset(self, seed: int | None = None) -> StepRecord:
        """Restart the mission; a given ``seed`` reseeds every component (same seed, same run)."""
        self.close()
        if seed is not None:
            self._build(int(seed))
        scn, parts = self.scenario, self.parts
        init_pos = np.asarray(scn.vehicle.initial_pos_ned, dtype=float)
        init_rpy = np.deg2rad(scn.vehicle.initial_rpy_deg)
        self.physics.reset(init_pos, init_rpy)
        for runner in self.surface_vehicles.values():
            runner.reset()
        if scn.comms.acoustic.enabled:  # a fresh channel and surface world model
            perception = self.parts.perception
            self.link = VehicleLink(scn, self.surface_vehicles[scn.comms.surface.vehicle],
                                    None if perception is None else perception.pmha,
                                    None if perception is None else perception.region_ned,
                                    () if perception is None else perception.class_names, self.parts.seed,
                                    footprint=None if perception is None else perception.sonar_footprint())
        self.thruster_cmd = np.zeros(self.physics.params.n_thrusters)
        self.wrench_body = np.zeros(6)
        parts.scheduler.reset(0.0)
        self.nav_filter = parts.make_nav_filter(scn)
        if self.link is not None and scn.comms.surface.usbl_fixes and scn.comms.surface.fuse_usbl_fixes:
            self.nav_filter = DelayedFixFilter(self.nav_filter, snapshot_every_s=0.25,
                                               gate_chi2=scn.autonomy.navigation.gps_gate_chi2)
        self._by_type: dict[type, list[Callable[[Any], Any]]] = {}
        for msg_type, handler in self.nav_filter.message_handlers().items():
            self._by_type.setdefault(msg_type, []).append(handler)
        self._by_type.setdefault(DvlMsg, []).append(self._note_bottom_lock)
        self._by_source: dict[str, Callable[[Any, NavEstimate], Any]] = {}
        if parts.perception is not None:
            self._by_source[parts.sonar.name] = parts.perception.process
        for name, process in parts.processors.items():
            getattr(process, "reset", lambda: None)()
            self._by_source[name] = process
        if parts.tracking is not None:  # target tracking: USBL fixes by type, frames of its sonar
            parts.tracking.reset()
            self._by_type.setdefault(UsblMsg, []).append(parts.tracking.on_usbl)
            self._by_source[parts.sonar.name] = lambda render, _nav: parts.tracking.on_frame(render.frame)
        parts.guidance.start(init_pos[:2], float(init_rpy[2]))
        parts.fsm.reset()
        parts.autopilot.reset()
        if parts.perception is not None:
            parts.perception.reset()
        #: Whether the sonars render their objects' ground truth and instance masks: some
        #: observer reads them (one without ``sonar_truth = False``; decided here, at reset).
        self.sonar_truth = any(getattr(o, "sonar_truth", True) for o in self.observers)
        for sensor in parts.sensors.values():
            if hasattr(sensor, "render_truth"):  # the forward-looking sonars (the pipeline's copy too)
                sensor.render_truth = self.sonar_truth
        # pipelined only where perception is a sink and the sonar's latency is fixed (the
        # scheduler gets a ticket, not the frame, to time the delivery by)
        if (self.workers > 1 and parts.perception is not None and parts.tracking is None
                and type(parts.sonar).latency_s is Sensor.latency_s):
            self._pipeline = SonarPipeline(self.physics, parts.sonar, parts.perception,
                                           frames=any(getattr(o, "sonar_frames", True) for o in self.observers))
        self.last_dvl_lock = True
        self._setpoint: Setpoint | None = None
        self._wall_start = time.perf_counter()
        self._wall_s = 0.0
        self._delivered: Counter[str] = Counter()
        #: (vehicle, vehicle) -> autonomy periods that ended with their hulls touching.
        self.vehicle_contacts: Counter[tuple[str, str]] = Counter()
        self._started = True
        info = self.info()
        for obs in self.observers:
            obs.on_start(info)
        self._truth = self.physics.truth()
        # t = 0: every sensor's first firing (delivered, as every message, at the first
        # autonomy tick at or after its delivery time: the autonomy first runs one period
        # on, so the estimate here is still the prior), the extra vehicles' first tick and,
        # when tracking, the first vehicle pose (the prior: the start of the pose history,
        # so that fixes measured before the first autonomy period find a pose)
        due = parts.scheduler.take_due(0.0)
        if due:
            self._fire_all(due, self._truth)
        for runner in self.surface_vehicles.values():
            runner.tick(self._truth.pos_ned, auv_truth=self._truth)
        self._others = self._other_truths()
        nav = self.nav_filter.estimate()
        if parts.tracking is not None:
            for res in parts.tracking.on_nav(nav):
                for obs in self.observers:
                    obs.on_message(parts.sonar.name, res)
        return self._record(self._truth, nav, "idle")

    @property
    def done(self) -> bool:
        return self.parts.fsm.done or self.t_s >= self.scenario.duration_s - 1e-9

    def step(self, setpoint: Setpoint | None = None) -> StepRecord:
        """Advance one autonomy period. ``setpoint`` overrides guidance (gym envs)."""
        physics, scheduler, timer = self.physics, self.parts.scheduler, self.timer
        truth = self._truth
        with timer.stage("physics"):
            physics_step, take_due, cmd = physics.step, scheduler.take_due, self.thruster_cmd
            dt, eps = physics.dt_s, scheduler.eps_s
            for _ in range(self.substeps):
                t_end = (physics.n_steps + 1) * dt
                if scheduler.next_fire_s < t_end - eps and truth.t_s != physics.t_s:
                    with timer.stage("truth"):  # a firing inside this step: the state at its start
                        truth = physics.truth()
                before = truth
                physics_step(cmd)
                due = take_due(physics.t_s)
                if due:
                    truth = self._fire_all(due, before)
        if truth.t_s != physics.t_s:  # not already taken for a sensor on the last substep
            with timer.stage("truth"):
                truth = physics.truth()
        self._truth = truth
        if self.surface_vehicles:
            with timer.stage("surface_vehicles"):
                for runner in self.surface_vehicles.values():
                    # a vessel with a USBL follows its own fixes of the AUV, else the AUV's true position
                    runner.tick(truth.pos_ned, auv_truth=truth)
                self._others = self._other_truths()
                for pair in physics.vehicles_in_contact():
                    self.vehicle_contacts[pair] += 1
        for name, msg in scheduler.pop_ready(physics.t_s):
            self._deliver(name, msg)
        if self.link is not None and self._pipeline is not None and self._pipeline.busy:
            # the link queues detections at the time they are handed over: take this step's
            # frames now, as the serial loop does (rendering still overlaps; same results)
            with timer.stage("pipeline_wait"):
                self._to_observers(self._pipeline.ready(wait=True))
        if self.link is not None:
            with timer.stage("link"):
                fixes = self.link.tick(physics.t_s, truth, self._others[self.link.node], timer)
            if isinstance(self.nav_filter, DelayedFixFilter):
                with timer.stage("nav_late_fix"):  # the re-processing is the link's cost
                    for fix in fixes:
                        self.nav_filter.on_late_fix(fix)
            with timer.stage("observers"):
                for fix in fixes:
                    for obs in self.observers:
                        obs.on_message(fix.source, fix)
        parts = self.parts
        with timer.stage("nav_filter"):
            self.nav_filter.predict(physics.t_s)
            nav = self.nav_filter.estimate()
        if parts.tracking is not None:
            with timer.stage("tracking"):
                results = parts.tracking.on_nav(nav)  # frames that waited for this pose
            with timer.stage("observers"):
                for res in results:
                    for obs in self.observers:
                        obs.on_message(parts.sonar.name, res)
        with timer.stage("guidance"):
            if setpoint is not None:
                sp = setpoint
            elif parts.buddy is not None:
                est = parts.tracking.primary.estimate(physics.t_s)
                sp = parts.buddy.update(nav, None if est is None else est[0][:3])
            else:
                sp = parts.fsm.update(physics.t_s, nav, self.last_dvl_lock)
        self._setpoint = sp
        with timer.stage("control"):
            self.wrench_body = np.zeros(6) if sp is None else parts.autopilot.update(nav, sp, self.autonomy_dt_s)
            self.thruster_cmd = parts.allocator.allocate(self.wrench_body)
        wrench_handlers = self._by_type.get(WrenchCmdMsg)
        if wrench_handlers:  # the speed model of a DVL-free filter; no message built for others
            with timer.stage("nav_filter"):
                cmd = WrenchCmdMsg(physics.t_s, self.wrench_body.copy())
                for handler in wrench_handlers:
                    handler(cmd)
        rec = self._record(truth, nav, parts.fsm.mode)
        if self._pipeline is not None and self._pipeline.busy:
            with timer.stage("perception"):  # this process's part: geolocalisation, world model
                ready = list(self._pipeline.ready())
            self._to_observers(ready)
        self._wall_s = time.perf_counter() - self._wall_start
        return rec

    def flush(self) -> None:
        """Wait for the pipelined sonar frames delivered so far and hand them to the observers
        (nothing to do in the serial loop)."""
        if self._pipeline is not None and self._pipeline.busy:
            with self.timer.stage("pipeline_wait"):
                self._to_observers(self._pipeline.ready(wait=True))
            self._wall_s = time.perf_counter() - self._wall_start

    def close(self) -> None:
        """Stop the pipeline's worker processes, if any, after copying their state back (frames
        delivered but not yet handed to the observers are dropped; :meth:`flush` first)."""
        if self._pipeline is not None:
            self._pipeline.close()
            self._pipeline = None

    def run(self, progress: bool = True) -> MissionSummary:
        """Run until the mission ends or the scenario's duration is reached."""
        from tqdm import tqdm

        if not getattr(self, "_started", False):
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
        self.flush()
        if self.link is not None:
            self.link.finish(self.t_s)
        summary = self.summary()
        for obs in self.observers:
            obs.on_end(summary)
        return summary

    def summary(self) -> MissionSummary:
        fsm = self.parts.fsm
        return MissionSummary(self.t_s, self._wall_s, fsm.done and not fsm.aborted, fsm.aborted,
                              fsm.abort_reason or "", fsm.mode, MappingProxyType(dict(self._delivered)))

    # -- internals -------------------------------------------------------------------
    def _fire_all(self, due: list[tuple[float, str]], before: VehicleTruth) -> VehicleTruth:
        """Fire the sensors of ``due`` (``(firing time, name)`` in time order, all within the
        step just taken, from ``before.t_s`` to now), each with the true state and the scene
        at its own time: the state now for a firing now, else the state interpolated between
        ``before`` and now (:func:`sim.truth.interpolate_truth`). Returns the state now."""
        physics, timer, eps = self.physics, self.timer, self.parts.scheduler.eps_s
        with timer.stage("truth"):
            now = physics.truth()
        inside = [(t, name) for t, name in due if t < now.t_s - eps]
        at_now = [name for t, name in due if t >= now.t_s - eps]
        k = 0
        while k < len(inside):  # firings between the steps, grouped by time
            t_fire = inside[k][0]
            with timer.stage("truth"):
                truth = interpolate_truth(before, now, t_fire)
                scene = physics.scene(t_fire)
            while k < len(inside) and inside[k][0] == t_fire:
                with timer.stage(f"sensor:{inside[k][1]}"):
                    self._fire(inside[k][1], truth, scene)
                k += 1
        if at_now:
            with timer.stage("truth"):
                scene = physics.scene()
            for name in at_now:
                with timer.stage(f"sensor:{name}"):
                    self._fire(name, now, scene)
        return now

    def _fire(self, name: str, truth: VehicleTruth, scene: SceneView) -> None:
        pipeline = self._pipeline
        if pipeline is not None and name == self.parts.sonar.name:
            msg = pipeline.capture(truth)  # rendered on a worker from a copy of the scene now
        else:
            msg = self.parts.sensors[name].measure(truth, scene)
        self.parts.scheduler.push(name, truth.t_s, msg)

    def _note_bottom_lock(self, msg: DvlMsg) -> None:
        self.last_dvl_lock = bool(msg.valid)

    def _deliver(self, name: str, msg: Any) -> None:
        self._delivered[name] += 1
        timer = self.timer
        if isinstance(msg, FrameTicket):  # pipelined: perception with the estimate of now (moved to the capture time)
            self._pipeline.deliver(name, msg, self.nav_filter.estimate())
            return
        with timer.stage("nav_filter"):
            for handler in self._by_type.get(type(msg), ()):
                handler(msg)
        process = self._by_source.get(name)
        if process is None:  # a navigation sensor's message: no result; straight to the observers
            if self.observers:
                with timer.stage("observers"):
                    for obs in self.observers:
                        obs.on_message(name, msg)
            return
        with timer.stage("perception"):
            result = process(msg, self.nav_filter.estimate())
        with timer.stage("nav_filter"):
            for handler in self._by_type.get(type(result), ()) if result is not None else ():
                handler(result)  # onboard results the filter fuses (position fixes)
        self._to_observers(((name, msg, result),))

    def _to_observers(self, ready) -> None:
        """Hand ``(name, message, result or None)`` triples to every observer, in order; with
        the acoustic link, perception results' detections go to the AUV's modem first."""
        ready = list(ready)
        link = self.link
        if link is not None and (self.parts.fsm.mode != "idle" or self.scenario.comms.surface.send_while_idle):
            with self.timer.stage("link"):
                for _, _, result in ready:
                    if isinstance(result, PerceptionResult):
                        link.send_detections(self.physics.t_s, result.localized)
        with self.timer.stage("observers"):
            for name, msg, result in ready:
                for obs in self.observers:
                    if msg is not None:  # None: a pipelined frame no observer takes
                        obs.on_message(name, msg)
                    if result is not None:
                        obs.on_message(name, result)

    def _other_truths(self) -> Mapping[str, VehicleTruth]:
        return MappingProxyType({name: self.physics.truth(name) for name in self.surface_vehicles})

    def _record(self, truth: VehicleTruth, nav: NavEstimate, mode: str) -> StepRecord:
        sp = self._setpoint
        nan = math.nan
        rec = StepRecord(
            t_s=self.t_s, truth=truth, nav=nav,
            setpoint_speed_mps=sp.speed_mps if sp else nan,
            setpoint_heading_rad=sp.heading_rad if sp else nan,
            setpoint_altitude_m=(sp.altitude_m if sp and sp.altitude_m is not None else nan),
            setpoint_depth_m=(sp.depth_m if sp and sp.depth_m is not None else nan),
            wrench_body=self.wrench_body.copy(), thruster_cmd=self.thruster_cmd.copy(), mode=mode,
            others=self._others,
        )
        with self.timer.stage("observers"):
            for obs in self.observers:
                obs.on_step(rec)
        return rec
