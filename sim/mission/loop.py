"""The closed-loop mission: physics, sensors and autonomy at their own rates, in one fixed loop.

:class:`Mission` runs the loop; :class:`sim.scene.physics.Physics` owns the world,
:func:`sim.mission.parts.build_mission_parts` builds the sensors and the core onboard stack,
and each study is a feature (:mod:`sim.features`, protocol :mod:`sim.features.base`) the
loop calls at fixed points. :meth:`Mission.step` advances one autonomy period and never grows
when a study is added ([dmcontrol2020]):

1. physics substeps, each sensor due in that time fired at its own time (the true state
   interpolated between the steps for a firing between them; every sensor first fires at
   t = 0, in :meth:`Mission.reset`); a feature may take a sensor's firing (``captures``);
2. the features' ``after_physics`` (extra vehicles);
3. delivery of the messages whose latency has passed: by type to the navigation filter's
   handlers and the features', by source to the onboard processing a feature registered; the
   results to the features' result handlers, then to the observers;
4. the features' ``before_nav`` (the pipelined perception's results of the period); the
   periodic events declared in the autonomy phase (the acoustic link); the navigation
   filter predicts to now; the features' ``after_nav`` (the trackers);
5. guidance: a gym env's setpoint, else the feature that drives the guidance (buddy), else the
   survey state machine; the autopilots and the thrust allocation;
6. the step record to the observers; the features' ``end_of_step`` (pipelined perception).

Observers receive every delivered message and every result by sensor name, the step
records, and immutable start and end summaries; they never take part in the loop's logic.
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
from autonomy.messages import DvlMsg, NavEstimate, WrenchCmdMsg
from scenarios.schema import Scenario
from sim.features import build_features
from sim.features.survey_perception import SurveyPerceptionFeature
from sim.features.base import LoopPorts, MissionFeature
from sim.mission.parts import NAV_SOURCES, MissionParts, build_mission_parts
from sim.scene.physics import Physics
from sim.events.scheduler import AUTONOMY
from sim.events.records import MissionInfo, MissionObserver, MissionSummary, StepRecord
from sim.sensors.base import SceneView
from sim.events.stage_timer import NULL_TIMER, StageTimer
from sim.dynamics.truth import VehicleTruth, interpolate_truth

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
            see :class:`sim.events.records.MissionObserver`); otherwise the frames' truth holds the
            sonar pose only (the images are the same bytes).
        perception: run ATR/localisation/world model on the sonar's frames (False: frames
            are still rendered at their rate when the sonar is enabled, but not processed).
        timer: a :class:`sim.events.stage_timer.StageTimer` to time the loop's stages (benchmarks);
            default: none.
        workers: processes the loop may use. 1: the serial loop. 2 or more: the sonar's frames
            and their ATR detection run in two worker processes (:mod:`sim.process.sonar_pipeline`) when
            nothing in the loop reads perception back (survey perception; not target tracking),
            with the serial loop's results bit for bit; observers get frames and perception
            results once ready, in order (frames only if an observer takes them: one with
            ``sonar_frames = True``). Call :meth:`close` when done (it ends the workers). The
            workers start with ``spawn``: a script that builds the mission needs the
            ``if __name__ == "__main__":`` guard.

        features: feature classes of the caller's own (:class:`sim.features.base.MissionFeature`),
            built after the shipped ones (:data:`sim.features.FEATURES`) and called after them.

    Attributes:
        features: the mission's features (:mod:`sim.features`), in the order the loop calls them.

    Raises:
        TypeError: ``scenario`` not a Scenario; a ``features`` entry not a MissionFeature subclass.
        ValueError: unknown ``nav_source``; ``workers`` < 1; a sensor mount site missing on the hull;
            more than one feature drives the guidance.
        sim.process.sonar_pipeline.PipelineError: (from :meth:`reset`, :meth:`step`, :meth:`run`) a
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
        features: Sequence[type[MissionFeature]] = (),
    ) -> None:
        if not isinstance(scenario, Scenario):
            raise TypeError(f"Mission: scenario must be a Scenario (scenarios.load_scenario(name)), got "
                            f"{type(scenario).__name__}")
        if nav_source not in NAV_SOURCES:
            raise ValueError(f"nav_source must be one of {NAV_SOURCES}, got {nav_source!r}")
        if int(workers) < 1:
            raise ValueError(f"workers must be >= 1, got {workers}")
        self.workers = int(workers)
        self._extra_features = tuple(features)
        self.scenario = scenario
        self.nav_source = nav_source
        self.observers = list(observers)
        self.timer = timer if timer is not None else NULL_TIMER
        self.perception_enabled = perception
        self.physics = Physics(scenario)
        self.dt_s = self.physics.dt_s
        self.substeps = max(int(round(scenario.physics.rate_hz / scenario.autonomy.rate_hz)), 1)
        self.autonomy_dt_s = self.substeps * self.dt_s
        self._started = False
        self._build(scenario.seed)

    def _build(self, seed: int) -> None:
        self.physics.reseed(seed)
        self.parts: MissionParts = build_mission_parts(self.scenario, self.physics, seed)
        self.features: tuple[MissionFeature, ...] = build_features(dict(
            scenario=self.scenario, physics=self.physics, parts=self.parts, seed=int(seed), nav_source=self.nav_source,
            perception=self.perception_enabled, workers=self.workers), self._extra_features)
        self._driver = next((f for f in self.features if f.drives_guidance), None)

    def feature(self, cls: type) -> Any:
        """The mission's feature of class ``cls`` (:mod:`sim.features`), or None when it has none."""
        return next((f for f in self.features if type(f) is cls), None)

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
        return any(f.captures for f in self.features)

    @property
    def worker_pids(self) -> list[int]:
        """Process ids of the features' worker processes (the sonar pipeline's), after :meth:`reset`."""
        return [pid for f in self.features for pid in f.worker_pids()]

    @property
    def perception(self):
        """The survey perception chain (:class:`sim.features.perception.Perception`; None without one);
        pipelined frames delivered so far are finished first."""
        feature = self.feature(SurveyPerceptionFeature)
        if feature is None:
            return None
        self.flush()
        return feature.results()

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
        self.thruster_cmd = np.zeros(self.physics.params.n_thrusters)
        self.wrench_body = np.zeros(6)
        parts.scheduler.reset(0.0)
        self.nav_filter = parts.make_nav_filter(scn)
        for feature in self.features:
            self.nav_filter = feature.wrap_nav_filter(self.nav_filter)
        self._by_type: dict[type, list[Callable[[Any], Any]]] = {}
        for msg_type, handler in self.nav_filter.message_handlers().items():
            self._by_type.setdefault(msg_type, []).append(handler)
        self._by_type.setdefault(DvlMsg, []).append(self._note_bottom_lock)
        self._by_source: dict[str, Callable[[Any, NavEstimate], Any]] = {}
        self._result_handlers: dict[type, list[Callable[[str, Any], None]]] = {}
        self._consumers: dict[type, Callable[[str, Any], None]] = {}
        self._events: dict[str, tuple[Callable[[VehicleTruth], None], str]] = {}
        parts.guidance.start(init_pos[:2], float(init_rpy[2]))
        parts.fsm.reset()
        parts.autopilot.reset()
        #: Whether the sonars render their objects' ground truth and instance masks: some
        #: observer reads them (one with ``sonar_truth = True``; decided here, at reset).
        self.sonar_truth = any(o.sonar_truth for o in self.observers)
        for sensor in parts.sensors.values():
            if sensor.ground_truth_optional:  # the forward-looking sonars (a pipeline's copy too)
                sensor.render_truth = self.sonar_truth
        ports = LoopPorts(self)
        for feature in self.features:
            feature.reset(ports)
        self._capture = {name: f for f in self.features for name in f.captures}
        self.last_dvl_lock = True
        self._setpoint: Setpoint | None = None
        self._wall_start = time.perf_counter()
        self._wall_s = 0.0
        self._delivered: Counter[str] = Counter()
        self._started = True
        info = self.info()
        for obs in self.observers:
            obs.on_start(info)
        self._truth = self.physics.truth()
        # t = 0: every sensor's first firing (delivered, as every message, at the first
        # autonomy tick at or after its delivery time: the autonomy first runs one period
        # on, so the estimate here is still the prior), then the features' start (the extra
        # vehicles' first tick, the trackers' first pose)
        due = parts.scheduler.take_due(0.0)
        if due:
            self._fire_all(due, self._truth)
        nav = self.nav_filter.estimate()
        for feature in self.features:
            feature.start(self._truth, nav)
        self._others = self._other_truths()
        return self._record(self._truth, nav, "idle")

    @property
    def done(self) -> bool:
        return self.parts.fsm.done or self.t_s >= self.scenario.duration_s - 1e-9

    def step(self, setpoint: Setpoint | None = None) -> StepRecord:
        """Advance one autonomy period. ``setpoint`` overrides guidance (gym envs)."""
        physics, timer, features = self.physics, self.timer, self.features
        with timer.stage("physics"):
            truth = self._advance(self._truth)
        self._truth = truth
        t_s = physics.t_s
        for feature in features:
            feature.after_physics(t_s, truth)
        if physics.extras:
            self._others = self._other_truths()
        for name, msg in self.parts.scheduler.pop_ready(t_s):
            self._deliver(name, msg)
        for feature in features:
            feature.before_nav(t_s, truth)
        for _, name in self.parts.scheduler.take_due(t_s, AUTONOMY):
            self._fire(name, truth, None)
        with timer.stage("nav_filter"):
            self.nav_filter.predict(t_s)
            nav = self.nav_filter.estimate()
        for feature in features:
            feature.after_nav(t_s, nav)
        parts = self.parts
        with timer.stage("guidance"):
            if setpoint is not None:
                sp = setpoint
            elif self._driver is not None:
                sp = self._driver.setpoint(t_s, nav)
            else:
                sp = parts.fsm.update(t_s, nav, self.last_dvl_lock)
        self._setpoint = sp
        with timer.stage("control"):
            self.wrench_body = np.zeros(6) if sp is None else parts.autopilot.update(nav, sp, self.autonomy_dt_s)
            self.thruster_cmd = parts.allocator.allocate(self.wrench_body)
        wrench_handlers = self._by_type.get(WrenchCmdMsg)
        if wrench_handlers:  # the speed model of a DVL-free filter; no message built for others
            with timer.stage("nav_filter"):
                cmd = WrenchCmdMsg(t_s, self.wrench_body.copy())
                for handler in wrench_handlers:
                    handler(cmd)
        rec = self._record(truth, nav, parts.fsm.mode)
        for feature in features:
            feature.end_of_step()
        self._wall_s = time.perf_counter() - self._wall_start
        return rec

    def flush(self) -> None:
        """Wait for the results still being made (pipelined sonar frames delivered so far) and
        hand them to the observers (nothing to do in the serial loop)."""
        for feature in self.features:
            feature.flush()
        if self._started:
            self._wall_s = time.perf_counter() - self._wall_start

    def close(self) -> None:
        """End the features' worker processes, if any, after copying their state back (results
        delivered but not yet handed to the observers are dropped; :meth:`flush` first)."""
        for feature in self.features:
            feature.close()

    def run(self, progress: bool = True) -> MissionSummary:
        """Run until the mission ends or the scenario's duration is reached."""
        from tqdm import tqdm

        if not self._started:
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
        for feature in self.features:
            feature.finish(self.t_s)
        summary = self.summary()
        for obs in self.observers:
            obs.on_end(summary)
        return summary

    def summary(self) -> MissionSummary:
        fsm = self.parts.fsm
        return MissionSummary(self.t_s, self._wall_s, fsm.done and not fsm.aborted, fsm.aborted,
                              fsm.abort_reason or "", fsm.mode, MappingProxyType(dict(self._delivered)))

    # -- internals -------------------------------------------------------------------
    def _advance(self, truth: VehicleTruth) -> VehicleTruth:
        """The physics substeps of one autonomy period, each sensor firing due in them at its
        own time; the true state at the period's end."""
        physics, scheduler, timer = self.physics, self.parts.scheduler, self.timer
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
        return truth

    def _fire_all(self, due: list[tuple[float, str]], before: VehicleTruth) -> VehicleTruth:
        """Fire the sensors of ``due`` (``(firing time, name)`` in time order, all within the
        step just taken, from ``before.t_s`` to now), each with the true state and the scene
        at its own time: the state now for a firing now, else the state interpolated between
        ``before`` and now (:func:`sim.dynamics.truth.interpolate_truth`). Returns the state now."""
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
                self._fire(inside[k][1], truth, scene)
                k += 1
        if at_now:
            scene = None
            for name in at_now:
                if scene is None and name not in self._events:
                    with timer.stage("truth"):
                        scene = physics.scene()
                self._fire(name, now, scene)
        return now

    def _fire(self, name: str, truth: VehicleTruth, scene: SceneView | None) -> None:
        event = self._events.get(name)
        if event is not None:  # a declared periodic event (at the autonomy ticks: the state now)
            with self.timer.stage(event[1]):
                event[0](truth)
            return
        with self.timer.stage(f"sensor:{name}"):
            self._measure(name, truth, scene)

    def _measure(self, name: str, truth: VehicleTruth, scene: SceneView) -> None:
        taker = self._capture.get(name)
        msg = taker.capture(name, truth) if taker is not None else self.parts.sensors[name].measure(truth, scene)
        self.parts.scheduler.push(name, truth.t_s, msg)

    def _note_bottom_lock(self, msg: DvlMsg) -> None:
        self.last_dvl_lock = bool(msg.valid)

    def _deliver(self, name: str, msg: Any) -> None:
        self._delivered[name] += 1
        timer = self.timer
        consumer = self._consumers.get(type(msg))
        if consumer is not None:  # a pipeline's ticket: the feature takes it from here
            consumer(name, msg)
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
        """Hand ``(name, message, result or None)`` triples to the features' result handlers
        (:meth:`sim.features.base.LoopPorts.on_result`), then to every observer, in order."""
        ready = list(ready)
        if self._result_handlers:
            for name, _, result in ready:
                for handler in self._result_handlers.get(type(result), ()) if result is not None else ():
                    handler(name, result)
        with self.timer.stage("observers"):
            for name, msg, result in ready:
                for obs in self.observers:
                    if msg is not None:  # None: a pipelined frame no observer takes
                        obs.on_message(name, msg)
                    if result is not None:
                        obs.on_message(name, result)

    def _other_truths(self) -> Mapping[str, VehicleTruth]:
        return MappingProxyType({name: self.physics.truth(name) for name in self.physics.extras})

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
