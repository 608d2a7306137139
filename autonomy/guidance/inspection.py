"""Active inspection guidance: a coarse coverage pass, then legs the world model asks for.

:class:`InspectionGuidance` has the interface of :class:`autonomy.guidance.survey.SurveyGuidance`
(``start``, ``update``, ``finished``, ``depth_m``/``altitude_m``, ``plan``), so the mission
state machine (:class:`autonomy.guidance.mission.MissionFsm`) flies it as it flies the
lawnmower, with the same aborts. It receives the world model at each update
(:meth:`InspectionGuidance.on_world_model`) and asks :class:`autonomy.guidance.inspection_planner.InspectionPlanner`
which objects to look at next ([P000] sections VI-VII: re-plan to inspect the detected
objects; never move for an object the model has not confirmed).

==========================  ==================================================================
phase                       what the vehicle does
==========================  ==================================================================
``coverage``                the coarse lawnmower (legs centred across the area)
``inspect``                 an inspection leg: towards one object on the planned heading
``done``                    nothing left to inspect, or the time budget is spent: hold; the
                            state machine surfaces
==========================  ==================================================================

Modes: ``coverage_then_inspect`` (the whole pass, then the tour of legs, re-planned after
each leg) and ``interleaved`` (a coverage leg is broken off for the confirmed, uncertain
objects it has passed, out of the sonar's view and within ``interleave_radius_m``; coverage
rejoins the coverage path at its point nearest the vehicle). A leg being flown is kept while its object stays confirmed and
not confident (else it is dropped); the tour after it is re-planned at every world-model update.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from autonomy.control.setpoint import Setpoint
from autonomy.frames import wrap_angle
from autonomy.guidance.config import InspectionConfig, LosConfig, SurveyConfig
from autonomy.guidance.inspection_planner import InspectionLeg, InspectionPlanner, PlannerParams, SurveyArea
from autonomy.guidance.lawnmower import LawnmowerPlan, plan_lawnmower
from autonomy.guidance.survey import SurveyGuidance
from autonomy.guidance.waypoints import WaypointManager
from autonomy.messages import NavEstimate


def survey_area(survey: SurveyConfig) -> SurveyArea:
    """The survey rectangle of a ``SurveyConfig`` (without its run-in)."""
    return SurveyArea(tuple(survey.origin_ne_m), math.radians(survey.leg_heading_deg), survey.length_m,
                      survey.width_m, 1.0 if survey.first_turn == "starboard" else -1.0)


def coverage_spacing_m(cfg: InspectionConfig, swath_width_m: float | None) -> float:
    """Coverage leg spacing: the configured one, or the swath times ``1 - swath_overlap``.

    Raises:
        ValueError: ``from_swath`` without a positive swath.
    """
    if cfg.coverage_spacing_m != "from_swath":
        return float(cfg.coverage_spacing_m)
    if swath_width_m is None or not swath_width_m > 0.0:
        raise ValueError("autonomy.guidance.inspection.coverage_spacing_m is 'from_swath' but the sonar swath is "
                         f"{swath_width_m!r}; give a forward-looking sonar or a numeric coverage_spacing_m")
    return float(swath_width_m) * (1.0 - cfg.swath_overlap)


def plan_coverage(survey: SurveyConfig, spacing_m: float) -> LawnmowerPlan:
    """The coarse pass over ``survey``'s rectangle: ``n = max(1, ceil(width / spacing))`` legs,
    each in the middle of its ``width / n`` band (one leg: the centre line)."""
    n = max(1, int(math.ceil(survey.width_m / spacing_m - 1e-9)))
    band = survey.width_m / n
    area = survey_area(survey)
    origin = np.asarray(survey.origin_ne_m, dtype=float) + 0.5 * band * area.across_ne
    return plan_lawnmower(origin_ne_m=(float(origin[0]), float(origin[1])), length_m=survey.length_m,
                          width_m=band * (n - 1), leg_heading_rad=area.heading_rad, leg_spacing_m=band if n > 1 else 1.0,
                          first_turn=survey.first_turn, run_in_m=survey.run_in_m, turn=survey.turn,
                          min_turn_radius_m=survey.min_turn_radius_m, arc_points=survey.arc_points)


def leg_ranges_m(cfg: InspectionConfig, altitude_m: float, tilt_rad: float,
                 vertical_beam_rad: float) -> tuple[float, float]:
    """(start, end) ground ranges of an inspection leg, m: the configured ones, or ``from_beam``:
    where a seabed object at ``altitude_m`` below the sonar lies a quarter of the vertical beam
    above and below the boresight (depressions ``tilt -/+ beam / 4``), ``g = h / tan(depression)``.

    Raises:
        ValueError: ``from_beam`` with a beam that does not reach the seabed at both ends.
    """
    if cfg.leg_start_range_m != "from_beam":
        return float(cfg.leg_start_range_m), float(cfg.leg_end_range_m)
    near_dep, far_dep = tilt_rad + 0.25 * vertical_beam_rad, tilt_rad - 0.25 * vertical_beam_rad
    if not (0.0 < far_dep < near_dep < 0.5 * math.pi):
        raise ValueError(f"autonomy.guidance.inspection leg ranges from_beam: the sonar's tilt {math.degrees(tilt_rad):.1f} "
                         f"deg and vertical beam {math.degrees(vertical_beam_rad):.1f} deg do not look down at the "
                         "seabed at both ends; give leg_start_range_m and leg_end_range_m in m")
    return altitude_m / math.tan(far_dep), altitude_m / math.tan(near_dep)


def planner_params(cfg: InspectionConfig, survey: SurveyConfig, *, range_sigma_m: float = 0.05,
                   azimuth_sigma_rad: float = 0.015, altitude_sigma_m: float = 0.1,
                   tilt_rad: float = math.radians(15.0), vertical_beam_rad: float = math.radians(20.0)) -> PlannerParams:
    """The planner's parameters from the config (the look model's sigmas from the localisation,
    the leg ranges from the sonar's tilt and vertical beam: :func:`leg_ranges_m`). In depth
    mode the survey's nominal ``altitude_m`` stands for the altitude."""
    start_m, end_m = leg_ranges_m(cfg, survey.altitude_m, tilt_rad, vertical_beam_rad)
    return PlannerParams(
        confirm_existence=cfg.confirm_existence, confirm_detections=cfg.confirm_detections,
        position_2sigma_m=cfg.position_2sigma_m, look_2sigma_m=cfg.look_2sigma_m,
        class_entropy_bits=cfg.class_entropy_bits, confident_existence=cfg.confident_existence,
        leg_start_range_m=start_m, leg_end_range_m=end_m, altitude_m=survey.altitude_m,
        range_sigma_m=range_sigma_m, altitude_sigma_m=altitude_sigma_m, azimuth_sigma_rad=azimuth_sigma_rad,
        aspect_sigma_m=cfg.aspect_sigma_m, reference_bias_sigma_m=cfg.reference_bias_sigma_m,
        aspect_bin_deg=cfg.aspect_bin_deg,
        max_legs_per_object=cfg.max_legs_per_object, area_margin_m=cfg.area_margin_m)


def rejoin_path(path_ne_m: np.ndarray, pos_ne_m: ArrayLike) -> np.ndarray:
    """The rest of a polyline ((k, 2) m) from its point nearest ``pos_ne_m``: that point, then
    the vertices after it (the part before it was in the sonar's view on the way back)."""
    path = np.asarray(path_ne_m, dtype=float).reshape(-1, 2)
    p = np.asarray(pos_ne_m, dtype=float)[:2]
    if len(path) == 1:
        return path.copy()
    a, b = path[:-1], path[1:]
    d = b - a
    L2 = np.maximum(np.sum(d * d, axis=1), 1e-12)
    u = np.clip(np.sum((p - a) * d, axis=1) / L2, 0.0, 1.0)
    q = a + u[:, None] * d
    k = int(np.argmin(np.linalg.norm(q - p, axis=1)))
    return np.vstack([q[k][None], path[k + 1:]])


@dataclass(frozen=True, slots=True)
class InspectionEvent:
    """One entry of the guidance's log: ``event`` is ``leg_start`` (the leg's first waypoint
    reached), ``leg_end``, ``leg_dropped``, ``break_off``, ``resume``, ``coverage_done``,
    ``confident`` (every confirmed object confident), ``budget`` or ``done``."""

    t_s: float
    event: str
    object_id: int | None = None
    pos_ne_m: tuple[float, float] | None = None
    detail: str = ""


class InspectionGuidance:
    """Coverage pass then inspection legs (see the module docstring).

    Args:
        coverage: the coarse pass (:func:`plan_coverage`).
        planner: the inspection planner.
        cfg: the inspection config.
        speed_mps: survey speed.
        los: LOS config.
        depth_m, altitude_m: exactly one, as :class:`SurveyGuidance`.
        fov_rad: the sonar's horizontal field of view (interleaved mode: an object outside it
            has been passed).

    Attributes:
        phase: ``coverage``, ``inspect`` or ``done``.
        leg: the inspection leg being flown (None outside one).
        planned: the tour after it, as last re-planned.
        events: the log (:class:`InspectionEvent`).
        confident_t_s: mission time the map first became confident (None: never).
    """

    def __init__(self, coverage: LawnmowerPlan, planner: InspectionPlanner, cfg: InspectionConfig, speed_mps: float,
                 los: LosConfig = LosConfig(), *, depth_m: float | None = None, altitude_m: float | None = None,
                 fov_rad: float = math.radians(130.0), coverage_spacing_m: float | None = None) -> None:
        self.plan = coverage
        #: The spacing the coverage pass was planned with, m (from the swath or the config).
        self.coverage_spacing_m = coverage_spacing_m
        self.planner = planner
        self.cfg = cfg
        self.fov_rad = float(fov_rad)
        self.follower = SurveyGuidance(coverage.waypoints_ne_m, speed_mps, los, depth_m=depth_m, altitude_m=altitude_m)
        self.follower.plan = coverage
        self.depth_m = depth_m
        self.altitude_m = altitude_m
        self._acceptance_m = los.acceptance_radius_m
        self._refine = not cfg.finish_when_confident
        self._reset_state()

    @classmethod
    def from_config(cls, survey: SurveyConfig, cfg: InspectionConfig, los: LosConfig, *,
                    swath_width_m: float | None = None, fov_rad: float = math.radians(130.0),
                    range_sigma_m: float = 0.05, azimuth_sigma_rad: float = 0.015,
                    altitude_sigma_m: float = 0.1, tilt_rad: float = math.radians(15.0),
                    vertical_beam_rad: float = math.radians(20.0)) -> "InspectionGuidance":
        """Build from the survey and inspection configs (:func:`plan_coverage`, :func:`planner_params`;
        ``tilt_rad`` / ``vertical_beam_rad``: the sonar's boresight depression and vertical beam).

        Raises:
            ValueError: see :func:`coverage_spacing_m`.
        """
        spacing = coverage_spacing_m(cfg, swath_width_m)
        coverage = plan_coverage(survey, spacing)
        planner = InspectionPlanner(planner_params(cfg, survey, range_sigma_m=range_sigma_m,
                                                   azimuth_sigma_rad=azimuth_sigma_rad,
                                                   altitude_sigma_m=altitude_sigma_m, tilt_rad=tilt_rad,
                                                   vertical_beam_rad=vertical_beam_rad), survey_area(survey))
        altitude_mode = survey.vertical_mode == "altitude"
        return cls(coverage, planner, cfg, survey.speed_mps, los, depth_m=None if altitude_mode else survey.depth_m,
                   altitude_m=survey.altitude_m if altitude_mode else None, fov_rad=fov_rad,
                   coverage_spacing_m=spacing)

    def _reset_state(self) -> None:
        self.phase = "coverage"
        self.leg: InspectionLeg | None = None
        self.planned: list[InspectionLeg] = []
        self.events: list[InspectionEvent] = []
        self.confident_t_s: float | None = None
        self.objects: tuple = ()
        self._pos = np.zeros(2)
        self._yaw = 0.0
        self._t_s = 0.0
        self._resume: np.ndarray | None = None  # interleaved: coverage waypoints left
        self._leg_started = False
        self._break_off: list[InspectionLeg] = []
        self._dirty = False
        self.planner.reset()

    # -- the SurveyGuidance interface -------------------------------------------------
    @property
    def finished(self) -> bool:
        return self.phase == "done"

    @property
    def pos_ne_m(self) -> np.ndarray:
        """(2,) the vehicle's position at the last update (navigation estimate), m NED."""
        return self._pos.copy()

    @property
    def mode_label(self) -> str:
        """``inspect`` while a leg is flown, else ``survey`` (the coverage pass)."""
        return "inspect" if self.phase == "inspect" else "survey"

    @property
    def errors(self):
        return self.follower.errors

    @property
    def manager(self) -> WaypointManager:
        return self.follower.manager

    def vertical_setpoint(self) -> dict[str, float | None]:
        return self.follower.vertical_setpoint()

    def start(self, pos_ne_m: ArrayLike, heading_rad: float = 0.0) -> None:
        self._reset_state()
        self.follower.manager = WaypointManager(self.plan.waypoints_ne_m, self._acceptance_m)
        self.follower.start(pos_ne_m, heading_rad)
        self._pos = np.asarray(pos_ne_m, dtype=float)[:2].copy()
        self._yaw = float(heading_rad)

    def on_world_model(self, t_s: float, objects: Sequence) -> None:
        """A world-model update (the objects of :meth:`autonomy.world_model.PMHA.world_model`):
        record the looks and re-plan the tour."""
        self.objects = tuple(objects)
        self._dirty = True
        self.planner.observe(self.objects, self._pos)
        if self.confident_t_s is None and self.phase != "coverage" and self.planner.map_confident(self.objects):
            self.confident_t_s = float(t_s)
            self._log(t_s, "confident")
        if self.phase != "done":
            self.planned = self.planner.plan(self._excluding_leg(self.objects), self._plan_from(), self._refine)

    def _excluding_leg(self, objects: Sequence) -> list:
        return [o for o in objects if self.leg is None or o.id != self.leg.object_id]

    def _plan_from(self) -> np.ndarray:
        return np.asarray(self.leg.end_ne_m) if self.leg is not None else self._pos

    def _log(self, t_s: float, event: str, object_id: int | None = None, detail: str = "") -> None:
        self.events.append(InspectionEvent(float(t_s), event, object_id, (float(self._pos[0]), float(self._pos[1])),
                                           detail))

    def _fly(self, waypoints: np.ndarray) -> None:
        self.follower.manager = WaypointManager(waypoints, self._acceptance_m)
        self.follower.manager.start(self._pos)

    def _finish(self, t_s: float, why: str) -> None:
        if self.leg is not None:
            self._log(t_s, "leg_dropped", self.leg.object_id, why)
            self.leg = None
        self.phase = "done"
        self.planned = []
        self._log(t_s, why)
        self._log(t_s, "done")

    def object_by_id(self, object_id: int):
        """The world-model object ``object_id`` of the last update, or None."""
        return next((o for o in self.objects if o.id == object_id), None)

    def _leg_still_wanted(self) -> str | None:
        """None when the current leg is still wanted, else why not."""
        obj = self.object_by_id(self.leg.object_id)
        if obj is None:
            return "object left the world model"
        if not self.planner.confirmed(obj):
            return "object no longer confirmed"
        if not self._refine and self.planner.confident(obj):
            return "object confident"
        return None

    def _next_leg(self, t_s: float) -> bool:
        """Start the next leg of the tour (re-planned now); False when there is none."""
        legs = self.planner.plan(self.objects, self._pos, self._refine)
        if self.cfg.mode == "interleaved" and self._resume is not None:
            ids = {leg.object_id for leg in self._break_off}
            legs = [leg for leg in legs if leg.object_id in ids]
        if not legs:
            return False
        self.leg = legs[0]
        self.planned = legs[1:]
        self._leg_started = False
        self.phase = "inspect"
        self._fly(np.array([self.leg.start_ne_m, self.leg.end_ne_m]))
        return True

    def _passed_candidates(self) -> list[InspectionLeg]:
        """Interleaved: legs for candidates outside the sonar's view, within the radius."""
        out = []
        for leg in self.planner.plan(self.objects, self._pos, self._refine):
            d = np.asarray(leg.object_ne_m) - self._pos
            rel = abs(float(wrap_angle(math.atan2(d[1], d[0]) - self._yaw)))
            if float(np.hypot(*d)) <= self.cfg.interleave_radius_m and rel > 0.5 * self.fov_rad:
                out.append(leg)
        return out

    def update(self, nav: NavEstimate) -> Setpoint:
        """Setpoint for the autopilots from the navigation estimate (as :meth:`SurveyGuidance.update`)."""
        t_s = float(nav.t_s)
        self._t_s = t_s
        self._pos = np.asarray(nav.pos_ned, dtype=float)[:2].copy()
        self.planner.set_navigation_covariance(nav.cov_pos_ned)
        self._yaw = float(nav.rpy_rad[2])
        if self.phase != "done" and t_s >= self.cfg.time_budget_s:
            self._finish(t_s, "budget")
        if self.phase == "coverage":
            m = self.follower.manager
            if self.cfg.mode == "interleaved" and self._dirty and m.index >= 1 and not m.finished:
                self._dirty = False  # on the coverage path (its first waypoint reached)
                passed = self._passed_candidates()
                if passed:
                    self._resume = np.vstack([self._pos[None], m.waypoints_ne_m[m.index:]])
                    self._break_off = passed
                    self._log(t_s, "break_off", passed[0].object_id,
                              "objects " + ",".join(str(leg.object_id) for leg in passed))
                    self._next_leg(t_s)
            if self.phase == "coverage" and self.follower.finished:
                self._log(t_s, "coverage_done")
                self._after_leg(t_s)
        elif self.phase == "inspect":
            why = self._leg_still_wanted()
            if why is not None:
                self._log(t_s, "leg_dropped", self.leg.object_id, why)
                self.leg = None
                self._after_leg(t_s)
            else:
                if not self._leg_started and self.follower.manager.index >= 1:
                    self._leg_started = True
                    self._log(t_s, "leg_start", self.leg.object_id)
                if self.follower.finished:
                    self.planner.leg_flown(self.leg.object_id)
                    self._log(t_s, "leg_end", self.leg.object_id)
                    self.leg = None
                    self._after_leg(t_s)
        return self.follower.update(nav)

    def _after_leg(self, t_s: float) -> None:
        """After the coverage or a leg: the next leg, else resume coverage, else done."""
        if self._next_leg(t_s):
            return
        if self._resume is not None:  # interleaved: rejoin the coverage path left, at its nearest point
            self._fly(rejoin_path(self._resume, self._pos))
            self._resume = None
            self._break_off = []
            self.phase = "coverage"
            self._log(t_s, "resume")
            return
        if self.planner.map_confident(self.objects):
            if self.confident_t_s is None:
                self.confident_t_s = t_s
                self._log(t_s, "confident")
            self._finish(t_s, "all confident" if not self._refine else "no legs left")
        else:
            self._finish(t_s, "no legs left")

    @property
    def goal(self) -> dict | None:
        """What the planner aims at now (for the recording): the phase, the leg's object and
        its start / end (m, NED), the planned tour's objects; None in ``done``."""
        if self.phase == "done":
            return None
        out: dict = {"phase": self.phase, "tour": [leg.object_id for leg in self.planned]}
        if self.leg is not None:
            out.update(object_id=self.leg.object_id, start_ne_m=self.leg.start_ne_m, end_ne_m=self.leg.end_ne_m,
                       heading_rad=self.leg.heading_rad)
        return out


__all__ = ["InspectionEvent", "InspectionGuidance", "coverage_spacing_m", "leg_ranges_m", "rejoin_path", "plan_coverage", "planner_params",
           "survey_area"]
