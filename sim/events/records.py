"""What the mission loop emits: step records, perception results, the run's info and summary,
and the observer protocol.

Outputs (CSV, plots, rerun recordings, metrics) are observers reading these records;
they never take part in the loop's logic.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from autonomy.messages import Detection, NavEstimate
from sim.dynamics.truth import VehicleTruth


@dataclass(frozen=True, slots=True)
class StepRecord:
    """State at one autonomy tick.

    Attributes:
        truth: true vehicle state.
        nav: navigation estimate the autonomy used.
        setpoint_speed_mps, setpoint_heading_rad, setpoint_altitude_m, setpoint_depth_m:
            what guidance asked for (NaN where unused).
        wrench_body: (6,) desired body wrench from the autopilots, N and N m.
        thruster_cmd: (n_thr,) normalised thruster commands in [-1, 1].
        mode: mission state-machine mode.
        others: true state of each extra vehicle (``scenario.vehicles``) by name.
    """

    t_s: float
    truth: VehicleTruth
    nav: NavEstimate
    setpoint_speed_mps: float
    setpoint_heading_rad: float
    setpoint_altitude_m: float
    setpoint_depth_m: float
    wrench_body: NDArray[np.float64]
    thruster_cmd: NDArray[np.float64]
    mode: str
    others: Mapping[str, VehicleTruth] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class PerceptionResult:
    """What perception made of one sonar frame (delivered to observers after the frame).

    Attributes:
        t_s: capture time of the frame, s.
        detections: ATR detections in the frame.
        localized: per detection, its geolocalised position (onboard estimate).
        world_objects: the world model after fusing the frame.
    """

    t_s: float
    detections: tuple[Detection, ...] = ()
    localized: tuple[Any, ...] = ()
    world_objects: tuple[Any, ...] = ()


@dataclass(frozen=True, slots=True)
class InspectionGoal:
    """What the inspection planner aims at, emitted when it changes.

    Attributes:
        t_s: mission time, s.
        phase: ``coverage``, ``inspect`` or ``done``.
        object_id: the world-model object of the leg being flown (None outside a leg).
        start_ne_m, end_ne_m: (2,) the leg, m NED (None outside a leg).
        tour: the objects of the legs planned after it, in order.
    """

    t_s: float
    phase: str
    object_id: int | None
    start_ne_m: tuple[float, float] | None
    end_ne_m: tuple[float, float] | None
    tour: tuple[int, ...]


@dataclass(frozen=True)
class MissionInfo:
    """The built mission as observers may see it (read-only).

    Attributes:
        scenario: the scenario flown.
        seed: root seed of this run.
        nav_source: pose used for geolocalisation (``estimate`` or ``truth``).
        seabed: the true seabed.
        objects: the scene objects (pose at start).
        waypoints_ne: (k, 2) survey plan, m.
        vehicle_envelope_m: (3,) hull bounding box (length, width, height), m.
        sensors: entry name -> kind of every sensor built, in firing order.
        sensor_mounts: entry name -> :class:`sim.sensors.base.Mount` of every sensor built
            (``pos_body_m`` (3,) FRD offset from the body origin, m; ``rpy_rad`` (3,) sensor
            axes -> body, rad).
        vehicle_envelopes_m: extra vehicle name -> (3,) its hull bounding box, m.
        perception_sonar: the sensor whose frames perception (or the tracker) reads; None:
            none. Other forward-looking sonars' frames are delivered to observers too.
    """

    scenario: Any
    seed: int
    nav_source: str
    seabed: Any
    objects: tuple[Any, ...]
    waypoints_ne: NDArray[np.float64]
    vehicle_envelope_m: tuple[float, ...]
    sensors: Mapping[str, str] = field(default_factory=dict)
    sensor_mounts: Mapping[str, Any] = field(default_factory=dict)
    vehicle_envelopes_m: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    perception_sonar: str | None = None


@dataclass(frozen=True)
class MissionSummary:
    """How a mission ended.

    Attributes:
        sim_time_s, wall_time_s: simulated and wall-clock time since reset, s.
        finished, aborted, abort_reason: outcome of the mission state machine.
        final_mode: the state machine's last mode.
        messages_delivered: sensor name -> messages delivered to the autonomy.
    """

    sim_time_s: float
    wall_time_s: float
    finished: bool
    aborted: bool
    abort_reason: str
    final_mode: str = ""
    messages_delivered: Mapping[str, int] = field(default_factory=dict)


class MissionObserver(Protocol):
    """Reader of the mission loop's outputs; it never takes part in the loop's logic.

    ``on_message`` receives every message delivered to the autonomy, by sensor name (an
    ``ImuMsg``, an FLS render, ...), and after a sonar frame the :class:`PerceptionResult`
    made of it under the same name (with target tracking, the
    :class:`autonomy.tracking.onboard.TrackingFrameResult` instead, once the frame is
    processed: at the first vehicle pose at or after its ping).

    Every observer declares ``sonar_frames`` and ``sonar_truth`` (:class:`ObserverBase`
    declares both True). An observer that ignores the sonar's renders sets ``sonar_frames = False``: the
    pipelined loop (:mod:`sim.process.sonar_pipeline`) then does not ship them from its render worker
    when no observer takes them, and passes only the perception results.

    An observer that does not read the forward-looking sonar's ground truth (a render's
    ``truth.objects``, ``truth.mask_polar``, ``truth.mask_fan``; its pose ``t_s``, ``pos_ned``,
    ``R_ns`` is always there) sets ``sonar_truth = False``: when every observer does, the
    sonar skips that truth (:meth:`sim.sensors.fls.FlsSensor.render` with ``truth=False``), and
    reading it raises :class:`sim.sensors.sonar.ground_truth.SonarTruthNotComputedError`.
    """

    sonar_frames: bool
    sonar_truth: bool

    def on_start(self, info: MissionInfo) -> None: ...

    def on_step(self, record: StepRecord) -> None: ...

    def on_message(self, name: str, msg: Any) -> None: ...

    def on_end(self, summary: MissionSummary) -> None: ...


class ObserverBase:
    """A :class:`MissionObserver` that reads everything (``sonar_frames`` and ``sonar_truth``
    True) and does nothing: subclasses override the hooks they need and declare what they
    do not read (the loop reads these declarations; it does not probe for them)."""

    sonar_frames: bool = True
    sonar_truth: bool = True

    def on_start(self, info: MissionInfo) -> None:
        pass

    def on_step(self, record: StepRecord) -> None:
        pass

    def on_message(self, name: str, msg: Any) -> None:
        pass

    def on_end(self, summary: MissionSummary) -> None:
        pass
