"""The protocol a study plugs into the mission loop with, and the loop's ports it may use.

The loop (:class:`sim.mission.loop.Mission`) is fixed: one autonomy period is physics (with the
sensor firings the scheduler orders), delivery of the messages that are due, navigation,
guidance, control and the step record. A study (target tracking, the sea trial's surface
vehicles and acoustic link, scanning-sonar localisation, the side-scan full mode, survey
perception itself) is a :class:`MissionFeature`: it declares what it handles and when it runs,
and the loop calls every feature at the same fixed points, in the order of
:data:`sim.features.FEATURES`. Adding a study adds a feature module and its config; the loop,
the outputs and the console summary loop over the features and do not change.

This is the shape of dm_control's fixed ``Environment.step`` [dmcontrol2020] with the events
a component declares, as a Drake system declares its own periodic events [drake].

What a feature may touch of the loop is in :class:`LoopPorts` (handed to :meth:`MissionFeature.reset`):
register message handlers by type and onboard processing by sensor, send results to the
observers, read the clock, the navigation filter and the mission mode. A feature never
receives the :class:`~sim.mission.loop.Mission` itself.

Hooks, in the order the loop calls them (every default does nothing):

==========================  ===================================================================
hook                        when
==========================  ===================================================================
``wrap_nav_filter``         reset: the navigation filter is made (a feature may wrap it)
``reset``                   reset: register handlers (:class:`LoopPorts`)
``start``                   reset, after the sensors' first firing at t = 0
``capture``                 a sensor of :attr:`captures` fires (the feature takes the firing)
``after_physics``           each period, after the physics substeps and sensor firings
(delivery)                  messages whose latency has passed go to their handlers
``before_nav``              each period, before the navigation filter predicts to now
(autonomy events)           the periodic events declared in the ``AUTONOMY`` phase
                            (:meth:`LoopPorts.every`: the acoustic link)
``after_nav``               each period, with the navigation estimate of now
``setpoint``                each period, for the feature that ``drives_guidance``: its setpoint
                            replaces the survey state machine's (a gym env's replaces both)
``end_of_step``             each period, after the step record
``flush`` / ``finish``      the run ends (results still pending; final accounting)
``close``                   the mission is closed (worker processes end)
==========================  ===================================================================

For a run's outputs (:func:`sim.mission.run.run_mission`) a feature may add
observers (:meth:`MissionFeature.observers`), metrics (:meth:`MissionFeature.add_metrics`),
map layers, files (:meth:`MissionFeature.write_outputs`) and lines of the console summary
(:meth:`MissionFeature.summary_lines`, from ``metrics.json`` alone).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from autonomy.control.setpoint import Setpoint
from autonomy.messages import NavEstimate
from scenarios.schema import Scenario
from sim.events.records import MissionObserver
from sim.events.scheduler import PHYSICS
from sim.dynamics.truth import VehicleTruth

if TYPE_CHECKING:
    from sim.mission.parts import MissionParts
    from sim.outputs.trajectory_log import TrajectoryLog
    from sim.scene.physics import Physics
    from sim.events.stage_timer import StageTimer


@dataclass(frozen=True)
class FeatureContext:
    """What a feature is built from.

    Attributes:
        scenario: the validated scenario.
        physics: the world (hull sites, seabed, movers, extra vehicles).
        parts: the core sensors and onboard stack (:class:`sim.mission.parts.MissionParts`).
        seed: root seed (a feature draws from ``sim.rng.component_rng(seed, name)``).
        nav_source: pose used for geolocalisation (``estimate`` or ``truth``).
        perception: whether the sonar's frames are to be processed (False: rendered only).
        workers: processes the loop may use (a feature may pipeline its work when > 1).
        features: the features built before this one, by class (a feature may read
            another's declared outputs, e.g. the sea trial reads survey perception's world model).
    """

    scenario: Scenario
    physics: Physics
    parts: MissionParts
    seed: int
    nav_source: str
    perception: bool
    workers: int
    features: Mapping[type, MissionFeature]


class LoopPorts:
    """The loop as a feature may use it (made by the loop at each reset).

    Registration (during :meth:`MissionFeature.reset`):
        :meth:`every`: a periodic event on the loop's one clock (the scheduler);
        :meth:`on_message`: a handler of every delivered message of a type (after the
        navigation filter's own handlers); :meth:`process_source`: the onboard processing of
        one sensor's messages, ``(msg, nav) -> result or None``; :meth:`on_result`: a handler
        of results of a type (perception results, tiles), called before the observers get
        them; :meth:`consume`: messages of a type that stop at the handler (a pipeline's
        tickets), neither filtered nor observed.

    Use (any time): :meth:`emit` to the observers, :attr:`t_s`, :attr:`others`, :attr:`mode`,
    :attr:`nav_filter`, :attr:`timer`, :attr:`observers` (read-only declared flags).
    """

    def __init__(self, loop: Any) -> None:
        self._loop = loop

    # -- registration ------------------------------------------------------------------
    def on_message(self, msg_type: type, handler: Callable[[Any], Any]) -> None:
        self._loop._by_type.setdefault(msg_type, []).append(handler)

    def process_source(self, name: str, process: Callable[[Any, NavEstimate], Any]) -> None:
        self._loop._by_source[name] = process

    def on_result(self, result_type: type, handler: Callable[[str, Any], None]) -> None:
        self._loop._result_handlers.setdefault(result_type, []).append(handler)

    def consume(self, msg_type: type, handler: Callable[[str, Any], None]) -> None:
        self._loop._consumers[msg_type] = handler

    def every(self, name: str, rate_hz: float, event: Callable[[VehicleTruth], None], *, stage: str,
              phase: str = PHYSICS) -> None:
        """Declare a periodic event to the loop's scheduler, timed as ``stage``.

        ``phase`` :data:`sim.events.scheduler.PHYSICS`: ``event(auv_truth)`` at the first
        autonomy tick at or after each ``k / rate_hz`` s (k = 0 at reset), ordered with the
        sensors' firings (after those of the same time). :data:`sim.events.scheduler.AUTONOMY`:
        ``event(auv_truth)`` at the first tick at or after each ``(k + 1) / rate_hz`` s, once
        the period's messages are delivered and the features' ``before_nav`` hooks have run,
        before the navigation filter predicts (an onboard process that reads what was
        delivered: the acoustic link), with the true state at the tick.

        Raises:
            ValueError: ``rate_hz`` not positive or above the autonomy rate; an unknown phase.
        """
        loop = self._loop
        loop.parts.scheduler.add(name, rate_hz, quantum_s=loop.autonomy_dt_s, phase=phase,
                                 offset_s=0.0 if phase == PHYSICS else 1.0 / rate_hz)
        loop._events[name] = (event, stage)

    def has_result_handler(self, result_type: type) -> bool:
        """Whether some feature handles results of ``result_type`` as they are made."""
        return bool(self._loop._result_handlers.get(result_type))

    # -- use -----------------------------------------------------------------------------
    def emit(self, name: str, msg: Any) -> None:
        """Hand ``msg`` to every observer under ``name``."""
        for obs in self._loop.observers:
            obs.on_message(name, msg)

    def to_observers(self, ready) -> None:
        """Hand ``(name, message or None, result or None)`` triples to the result handlers,
        then to the observers, in order (as a delivered message's processing is)."""
        self._loop._to_observers(ready)

    @property
    def t_s(self) -> float:
        return self._loop.physics.t_s

    @property
    def autonomy_rate_hz(self) -> float:
        """The loop's period as a rate (the fastest a declared event may run), Hz."""
        return 1.0 / self._loop.autonomy_dt_s

    @property
    def others(self) -> Mapping[str, VehicleTruth]:
        """True state of each extra vehicle now, by name (what the step record carries)."""
        return self._loop._others

    @property
    def mode(self) -> str:
        """The survey state machine's mode (``idle`` before the dive)."""
        return self._loop.parts.fsm.mode

    @property
    def nav_filter(self) -> Any:
        return self._loop.nav_filter

    @property
    def timer(self) -> StageTimer:
        return self._loop.timer

    @property
    def observers(self) -> tuple[MissionObserver, ...]:
        return tuple(self._loop.observers)


class MissionFeature:
    """One study in the mission loop (see the module docstring for the hooks and their order).

    Subclasses set :attr:`name`, implement :meth:`build` and the hooks they need.

    Declared capabilities:
        name: the feature's name.
        captures: sensor names whose firings this feature takes instead of the sensor's
            ``measure`` (a pipeline rendering on a worker); set by :meth:`reset`.
        drives_guidance: the feature's :meth:`setpoint` replaces the survey state machine,
            which then does not run: its aborts (safe depth band, minimum altitude, DVL-lock and
            navigation timeouts) and its modes do not apply (the mode stays ``idle``), and the
            loop does not stop at contact; the feature keeps the vehicle safe itself. At most one
            feature of a mission declares it.
    """

    name: ClassVar[str] = "feature"
    captures: frozenset[str] = frozenset()
    drives_guidance: bool = False

    @classmethod
    def build(cls, ctx: FeatureContext) -> MissionFeature | None:
        """The feature for the mission of ``ctx``, or None when the mission does not have it."""
        raise NotImplementedError(f"{cls.__name__}.build(ctx): return the feature for this mission "
                                  "(e.g. cls(ctx)), or None when it does not apply")

    @classmethod
    def runs_to_duration(cls, scenario: Scenario) -> bool:
        """Whether ``scenario``'s mission, with this feature, runs to ``duration_s`` by design."""
        return False

    # -- the loop ------------------------------------------------------------------------
    def wrap_nav_filter(self, nav_filter: Any) -> Any:
        return nav_filter

    def reset(self, ports: LoopPorts) -> None:
        pass

    def start(self, truth: VehicleTruth, nav: NavEstimate) -> None:
        pass

    def capture(self, name: str, truth: VehicleTruth) -> Any:
        raise NotImplementedError(f"{type(self).__name__} declares no captures")

    def after_physics(self, t_s: float, truth: VehicleTruth) -> None:
        pass

    def before_nav(self, t_s: float, truth: VehicleTruth) -> None:
        pass

    def after_nav(self, t_s: float, nav: NavEstimate) -> None:
        pass

    def setpoint(self, t_s: float, nav: NavEstimate) -> Setpoint | None:
        return None

    def end_of_step(self) -> None:
        pass

    def flush(self) -> None:
        pass

    def finish(self, t_s: float) -> None:
        pass

    def close(self) -> None:
        pass

    def worker_pids(self) -> list[int]:
        """Process ids of the feature's worker processes (none by default)."""
        return []

    # -- a run's outputs -------------------------------------------------------------------
    def observers(self, options: Mapping[str, Any]) -> list[MissionObserver]:
        """Evaluation observers of a run (added before the recorders); ``options`` holds the
        run's choices (``score_detections``)."""
        return []

    def add_metrics(self, metrics: dict[str, Any], log: TrajectoryLog) -> None:
        """Add this feature's figures to ``metrics`` (metrics.json), in place."""

    def map_layers(self, layers: dict[str, Any]) -> None:
        """Change the map's layers (keyword arguments of :func:`sim.outputs.map_plot.plot_map`) in place."""

    def write_outputs(self, out_dir: Path, metrics: dict[str, Any], title: str) -> None:
        """Write this feature's files into the run folder."""

    @classmethod
    def summary_lines(cls, metrics: Mapping[str, Any]) -> list[str]:
        """Lines of the console summary, from ``metrics`` (metrics.json) alone."""
        return []

    def progress_label(self) -> str | None:
        """What the progress display shows instead of the state machine's mode (None: the mode)."""
        return None

    def planned_length_s(self) -> float | None:
        """The mission's planned length when this feature decides it (None: the survey's)."""
        return None


def fmt_or_na(value: float | None, spec: str, unit: str = "") -> str:
    """``value`` formatted for a summary line, or ``n/a`` when there is none (nothing matched)."""
    if value is None or value != value:  # None or NaN
        return "n/a"
    return f"{value:{spec}}{unit}"


__all__ = ["FeatureContext", "LoopPorts", "MissionFeature", "fmt_or_na"]
