"""Survey guidance: lawnmower waypoints followed with LOS, producing autopilot setpoints."""

from __future__ import annotations

import math
import numpy as np
from numpy.typing import ArrayLike

from autonomy.control.setpoint import Setpoint
from autonomy.frames import wrap_angle
from autonomy.guidance.config import LosConfig, SurveyConfig
from autonomy.guidance.lawnmower import LawnmowerPlan, plan_lawnmower
from autonomy.guidance.los import PathErrors, los_course_rad
from autonomy.guidance.waypoints import WaypointManager
from autonomy.messages import NavEstimate


def plan_from_config(survey_cfg: SurveyConfig, swath_width_m: float | None = None) -> LawnmowerPlan:
    """Lawnmower plan of a ``SurveyConfig``.

    ``swath_width_m`` (e.g. from :func:`autonomy.guidance.lawnmower.fls_swath_width_m`) is
    required when ``leg_spacing_m`` is ``"from_swath"``; the spacing is then
    ``swath * (1 - swath_overlap)``.
    """
    spacing = survey_cfg.leg_spacing_m
    if spacing == "from_swath":
        if swath_width_m is None or not swath_width_m > 0.0:
            raise ValueError(
                "autonomy.guidance.survey.leg_spacing_m is 'from_swath' but the sonar swath is "
                f"{swath_width_m!r}; give a positive swath width or a numeric leg_spacing_m"
            )
        spacing = swath_width_m * (1.0 - survey_cfg.swath_overlap)
    return plan_lawnmower(
        origin_ne_m=tuple(survey_cfg.origin_ne_m),
        length_m=survey_cfg.length_m,
        width_m=survey_cfg.width_m,
        leg_heading_rad=math.radians(survey_cfg.leg_heading_deg),
        leg_spacing_m=float(spacing),
        first_turn=survey_cfg.first_turn,
        run_in_m=survey_cfg.run_in_m,
        turn=survey_cfg.turn,
        min_turn_radius_m=survey_cfg.min_turn_radius_m,
        arc_points=survey_cfg.arc_points,
    )


class SurveyGuidance:
    """Follows a list of waypoints with LOS at constant speed and depth or altitude.

    Course control: with ``sideslip_compensation`` the heading setpoint is the LOS course
    minus the low-pass-filtered sideslip ``beta = atan2(v, u)`` measured over ground (DVL),
    so a cross current is crabbed into instead of pushing the vehicle off the line. Surge
    speed drops linearly with heading error, to ``min_speed_fraction`` at
    ``slow_down_heading_error_deg``, so turns stay tight.

    With ``heading_rad`` (NED, rad) an omnidirectional vehicle holds that heading and moves
    along the LOS course by surge ``V cos(course - yaw)`` and sway ``V sin(course - yaw)``
    (body frame, starboard > 0), no sideslip compensation or slow-down.

    Call :meth:`start` once with the current position, then :meth:`update` at the
    autonomy rate. After the last waypoint :attr:`finished` is True and the setpoint holds
    heading with zero speed.
    """

    def __init__(
        self,
        waypoints_ne_m: ArrayLike,
        speed_mps: float,
        los: LosConfig = LosConfig(),
        depth_m: float | None = None,
        altitude_m: float | None = None,
        heading_rad: float | None = None,
    ) -> None:
        if not speed_mps > 0.0:
            raise ValueError(f"speed_mps must be > 0, got {speed_mps}")
        if (depth_m is None) == (altitude_m is None):
            raise ValueError("SurveyGuidance needs exactly one of depth_m or altitude_m")
        self.manager = WaypointManager(waypoints_ne_m, los.acceptance_radius_m)
        self.speed_mps = float(speed_mps)
        self.los = los
        self._max_sideslip_rad = math.radians(los.max_sideslip_deg)
        self._slow_down_heading_error_rad = math.radians(los.slow_down_heading_error_deg)
        self.depth_m = depth_m
        self.altitude_m = altitude_m
        self.sideslip_rad = 0.0
        self.errors: PathErrors | None = None
        self.plan: LawnmowerPlan | None = None
        self._last_t_s: float | None = None
        self._hold_heading_rad = 0.0
        self.fixed_heading_rad = None if heading_rad is None else float(heading_rad)

    @classmethod
    def from_config(
        cls, survey_cfg: SurveyConfig, los_cfg: LosConfig, swath_width_m: float | None = None
    ) -> "SurveyGuidance":
        """Build from ``SurveyConfig`` and ``LosConfig`` (see :func:`plan_from_config`)."""
        plan = plan_from_config(survey_cfg, swath_width_m)
        altitude_mode = survey_cfg.vertical_mode == "altitude"
        guidance = cls(
            plan.waypoints_ne_m,
            survey_cfg.speed_mps,
            los_cfg,
            depth_m=None if altitude_mode else survey_cfg.depth_m,
            altitude_m=survey_cfg.altitude_m if altitude_mode else None,
            heading_rad=None if survey_cfg.heading_deg is None else math.radians(survey_cfg.heading_deg),
        )
        guidance.plan = plan
        return guidance

    #: The mission mode while this guidance flies (:attr:`autonomy.guidance.mission.MissionFsm.mode`).
    mode_label = "survey"

    @property
    def finished(self) -> bool:
        return self.manager.finished

    def start(self, pos_ne_m: ArrayLike, heading_rad: float = 0.0) -> None:
        self.manager.start(pos_ne_m)
        self.sideslip_rad = 0.0
        self._last_t_s = None
        self._hold_heading_rad = float(heading_rad)

    def vertical_setpoint(self) -> dict[str, float | None]:
        return {"depth_m": self.depth_m, "altitude_m": self.altitude_m}

    def update(self, nav: NavEstimate) -> Setpoint:
        """Setpoint for the autopilots from the current navigation estimate."""
        yaw = float(nav.rpy_rad[2])
        dt_s = 0.0 if self._last_t_s is None else max(nav.t_s - self._last_t_s, 0.0)
        self._last_t_s = nav.t_s
        u, v = float(nav.vel_body_mps[0]), float(nav.vel_body_mps[1])
        if self.los.sideslip_compensation and u > 0.1 and np.isfinite(v):
            beta = float(np.clip(math.atan2(v, u), -self._max_sideslip_rad, self._max_sideslip_rad))
            alpha = dt_s / (self.los.sideslip_filter_tau_s + dt_s) if dt_s > 0.0 else 0.0
            self.sideslip_rad += alpha * (beta - self.sideslip_rad)

        self.errors = self.manager.update(nav.pos_ned[:2], nav.t_s)
        if self.errors is None:
            return Setpoint(0.0, self._hold_heading_rad, **self.vertical_setpoint())

        course = los_course_rad(self.errors, self.los.lookahead_m)
        if self.fixed_heading_rad is not None:  # omnidirectional: along the course by surge and sway
            rel = course - yaw
            self._hold_heading_rad = self.fixed_heading_rad
            return Setpoint(self.speed_mps * math.cos(rel), self.fixed_heading_rad, sway_mps=self.speed_mps * math.sin(rel),
                            **self.vertical_setpoint())
        comp = self.sideslip_rad if self.los.sideslip_compensation else 0.0
        heading = float(wrap_angle(course - comp))
        self._hold_heading_rad = heading
        heading_err = abs(float(wrap_angle(heading - yaw)))
        frac = max(self.los.min_speed_fraction, 1.0 - heading_err / self._slow_down_heading_error_rad)
        return Setpoint(self.speed_mps * frac, heading, **self.vertical_setpoint())
