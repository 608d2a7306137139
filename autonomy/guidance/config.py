"""Guidance configs: lawnmower survey, LOS path following, mission state machine.

Frames: NED metres, headings in degrees clockwise from north in the config (converted to
radians by the consumers).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from autonomy.config_base import NonNegFloat, PositiveFloat, StrictModel, Vec2


class SurveyConfig(StrictModel):
    """Lawnmower survey over a rectangle in NED.

    The rectangle starts at corner ``origin_ne_m``; legs run along ``leg_heading_deg`` for
    ``length_m``; successive legs step ``leg_spacing_m`` to starboard of the first leg's
    direction (port when ``first_turn`` is ``port``) until ``width_m`` is covered. With
    ``leg_spacing_m: from_swath`` the spacing is the sonar's seabed swath at the survey
    altitude times ``1 - swath_overlap``.
    """

    origin_ne_m: Vec2 = Field((0.0, 0.0), description="first corner of the area (start of leg 1)")
    length_m: PositiveFloat = Field(30.0, le=10000.0, description="leg length along leg_heading_deg")
    width_m: float = Field(16.0, ge=0.0, le=10000.0, description="across-leg extent of the area")
    leg_heading_deg: float = Field(0.0, ge=-360.0, le=360.0, description="direction of leg 1")
    first_turn: Literal["starboard", "port"] = "starboard"
    leg_spacing_m: PositiveFloat | Literal["from_swath"] = Field(4.0, description="m, or from_swath")
    swath_overlap: float = Field(0.3, ge=0.0, lt=1.0, description="fraction of swath overlapping")
    run_in_m: NonNegFloat = Field(0.0, le=1000.0, description="straight extension before/after each leg")
    turn: Literal["corner", "arc"] = Field("arc", description="leg-to-leg turn: sharp corners or a semicircle")
    min_turn_radius_m: PositiveFloat = Field(1.0, le=1000.0, description="arcs tighter than this use corners")
    arc_points: int = Field(6, ge=2, le=90, description="waypoints per turn arc")
    vertical_mode: Literal["altitude", "depth"] = "altitude"
    altitude_m: float = Field(2.0, gt=0.0, le=100.0, description="survey altitude above seabed")
    depth_m: float = Field(2.0, gt=0.0, le=6000.0, description="survey depth (depth mode)")
    speed_mps: float = Field(0.5, gt=0.0, le=3.0)
    heading_deg: float | None = Field(
        None, ge=-360.0, le=360.0,
        description="hold this heading (NED deg) and move along the path by surge and sway: an omnidirectional "
                    "vehicle (BlueROV2 Heavy) looking one way while it moves; None: head along the path")


class LosConfig(StrictModel):
    """Line-of-sight path following."""

    lookahead_m: PositiveFloat = Field(3.0, le=1000.0, description="LOS lookahead distance Delta")
    acceptance_radius_m: PositiveFloat = Field(1.0, le=1000.0, description="waypoint reached inside this")
    sideslip_compensation: bool = Field(True, description="steer course, not heading (uses DVL sway)")
    max_sideslip_deg: float = Field(30.0, ge=0.0, le=80.0)
    sideslip_filter_tau_s: PositiveFloat = Field(5.0, le=600.0)
    slow_down_heading_error_deg: float = Field(
        45.0, gt=0.0, le=180.0,
        description="surge speed falls linearly with heading error, to the floor at this error",
    )
    min_speed_fraction: float = Field(0.2, ge=0.0, le=1.0, description="floor of the slow-down")


class MissionConfig(StrictModel):
    """Mission state machine: idle -> dive -> survey -> surface -> done; abort surfaces."""

    start_delay_s: NonNegFloat = Field(0.0, le=3600.0)
    dive_tolerance_m: PositiveFloat = Field(0.3, le=100.0, description="vertical error to end the dive")
    dive_settle_s: NonNegFloat = Field(3.0, le=600.0, description="time inside tolerance to end the dive")
    dive_timeout_s: PositiveFloat = Field(120.0, le=3600.0)
    surface_depth_m: PositiveFloat = Field(0.3, le=10.0, description="shallower than this counts as surfaced")
    safe_depth_min_m: NonNegFloat = Field(0.5, le=6000.0, description="survey abort if shallower")
    safe_depth_max_m: PositiveFloat = Field(10.0, le=6000.0, description="abort if deeper, any state")
    min_altitude_m: NonNegFloat = Field(0.5, le=100.0, description="abort if closer to the seabed")
    bottom_lock_timeout_s: PositiveFloat = Field(10.0, le=3600.0, description="abort after losing DVL lock this long")
    nav_timeout_s: PositiveFloat = Field(2.0, le=600.0, description="abort if no navigation this long")
    max_mission_time_s: PositiveFloat = Field(3600.0, le=86400.0)

    @model_validator(mode="after")
    def _band(self) -> "MissionConfig":
        if self.safe_depth_min_m >= self.safe_depth_max_m:
            raise ValueError("safe_depth_min_m must be < safe_depth_max_m")
        return self


class BuddyConfig(StrictModel):
    """Buddy observer (paper 004's diver-following use): keep the tracked target ahead, in the
    sonar's field of view, at ``distance_m``.

    ``behaviour``: ``hover`` (station at the start heading and depth whatever the target does:
    the paper's static vehicle, which sees the target only when it swims through the view),
    ``hold`` (no surge, only turn to face the target) or ``follow`` (also close or open the range to ``distance_m``). Surge
    ``gain_per_s * (range - distance_m)`` clipped to ``max_speed_mps``, never closer than
    ``min_distance_m`` (backs off); the vehicle holds ``depth_m`` or, when None, the target's
    estimated depth minus ``depth_offset_m`` (above it, so a tilted sonar looks down at it).
    """

    enabled: bool = False
    behaviour: Literal["hover", "hold", "follow"] = "follow"
    distance_m: PositiveFloat = Field(4.0, le=50.0)
    min_distance_m: PositiveFloat = Field(1.5, le=50.0)
    gain_per_s: PositiveFloat = Field(0.3, le=5.0)
    max_speed_mps: PositiveFloat = Field(0.6, le=3.0)
    depth_m: NonNegFloat | None = None
    depth_offset_m: float = Field(0.5, ge=-20.0, le=20.0)


class InspectionConfig(StrictModel):
    """Active inspection: the world model drives the vehicle (:mod:`autonomy.guidance.inspection`).

    When enabled, the survey rectangle of ``survey`` is covered by a coarse pass (legs
    ``coverage_spacing_m`` apart, centred across the area; ``from_swath``: the sonar's seabed
    swath times ``1 - swath_overlap``) and the world model's confirmed, not yet confident
    objects are then inspected by legs flown towards them (:mod:`autonomy.guidance.inspection_planner`
    for the tests). ``mode``: ``coverage_then_inspect`` (the pass, then the legs) or
    ``interleaved`` (a coverage leg is broken off to inspect objects it has passed, then
    resumed where it was left). The mission ends when every confirmed object is confident
    (``finish_when_confident``) or at mission time ``time_budget_s``. Speed and altitude (or
    depth) are the survey's. Disabled: the lawnmower of ``survey``, unchanged.
    """

    enabled: bool = False
    mode: Literal["coverage_then_inspect", "interleaved"] = "coverage_then_inspect"
    coverage_spacing_m: PositiveFloat | Literal["from_swath"] = Field(
        "from_swath", description="m between coverage legs, or from_swath")
    swath_overlap: float = Field(0.3, ge=0.0, lt=1.0, description="fraction of the swath coverage legs overlap")
    time_budget_s: PositiveFloat = Field(600.0, le=86400.0, description="mission time (s from start) to stop inspecting")
    finish_when_confident: bool = Field(
        True, description="end when every confirmed object is confident; false: keep inspecting "
        "(up to max_legs_per_object each) until the time budget")
    confirm_existence: float = Field(0.9, ge=0.0, le=1.0, description="existence to count an object confirmed")
    confirm_detections: int = Field(5, ge=1, le=100000, description="detections to count an object confirmed")
    position_2sigma_m: PositiveFloat = Field(1.0, le=100.0, description="confident: world-model 2-sigma semi-major below")
    look_2sigma_m: PositiveFloat = Field(0.45, le=100.0, description="confident: looks' predicted 2-sigma semi-major below")
    class_entropy_bits: float = Field(0.5, ge=0.0, le=1.0, description="confident: class entropy below (bits)")
    confident_existence: float = Field(0.99, ge=0.0, le=1.0, description="confident: existence above")
    leg_start_range_m: PositiveFloat | Literal["from_beam"] = Field(
        12.0, description="an inspection leg starts this far (m ground range) from its object; from_beam: where the "
        "object lies a quarter of the vertical beam above the boresight at the survey altitude")
    leg_end_range_m: PositiveFloat | Literal["from_beam"] = Field(
        5.0, description="and ends this far from it; from_beam: a quarter of the vertical beam below the boresight "
        "(12 / 5 m measured better than from_beam on mixed_targets_rough at 2.5 m altitude)")
    aspect_sigma_m: PositiveFloat = Field(
        0.3, le=10.0, description="where-on-the-object error of one aspect (look model): cssn_lawnmower's world "
        "after one coverage pass is off by 0.24-0.36 m")
    reference_bias_sigma_m: NonNegFloat = Field(
        0.0, le=10.0, description="look model: the box's reference point (its leading edge) lies this far (one "
        "sigma; an object's radius) before the object's centre along every line of sight, the same for all "
        "looks at it, so looks from opposite sides cancel it; 0: no such bias (legs may be flown either way)")
    aspect_bin_deg: float = Field(30.0, ge=5.0, le=180.0, description="looks closer in bearing count as one aspect")
    max_legs_per_object: int = Field(2, ge=1, le=100, description="inspection legs per object at most")
    area_margin_m: NonNegFloat = Field(2.0, le=100.0, description="legs stay inside the survey area grown by this")
    interleave_radius_m: PositiveFloat = Field(15.0, le=1000.0, description="interleaved: break off for objects within this")

    @model_validator(mode="after")
    def _legs(self) -> "InspectionConfig":
        numeric = [v for v in (self.leg_start_range_m, self.leg_end_range_m) if v != "from_beam"]
        if len(numeric) == 1:
            raise ValueError("leg_start_range_m and leg_end_range_m: give both in m or leave both from_beam")
        if numeric and not self.leg_start_range_m > self.leg_end_range_m:
            raise ValueError(f"leg_start_range_m ({self.leg_start_range_m}) must be greater than leg_end_range_m "
                             f"({self.leg_end_range_m})")
        if self.confident_existence < self.confirm_existence:
            raise ValueError("confident_existence must be >= confirm_existence")
        return self


class GuidanceConfig(StrictModel):
    survey: SurveyConfig = SurveyConfig()
    inspection: InspectionConfig = InspectionConfig()
    buddy: BuddyConfig = BuddyConfig()
    los: LosConfig = LosConfig()
    mission: MissionConfig = MissionConfig()
