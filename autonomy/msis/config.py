"""Onboard settings of the scanning-sonar localisation (pool circle or tank walls, [P002])."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from autonomy.config_base import PositiveFloat, StrictModel, Vec2


class MsisLocalizationConfig(StrictModel):
    """Position fixes from the scanning sonar against a known pool or tank outline.

    ``method``: ``none``; ``circle`` (a circular pool of ``pool_radius_m`` centred at
    ``centre_ne_m``); ``walls`` (a rectangular tank of ``tank_size_ne_m``, walls along north and
    east, centred at ``centre_ne_m``). A fix is made once the buffer holds ``min_points``
    points and ``fix_interval_s`` has passed since the last one (about a sweep), then the
    buffer starts afresh (its points were placed with the uncorrected estimate).
    """

    method: Literal["none", "circle", "walls"] = "none"
    centre_ne_m: Vec2 = (0.0, 0.0)
    pool_radius_m: PositiveFloat = Field(6.0, le=1000.0)
    tank_size_ne_m: tuple[PositiveFloat, PositiveFloat] = (20.0, 10.0)
    threshold_u8: int = Field(200, ge=1, le=255, description="echo threshold on the raw samples")
    echo_mode: Literal["first", "first_centre", "peaks"] = Field(
        "first_centre", description="echo range per ping (autonomy.msis.sonar_buffer.echo_ranges_m)")
    min_range_m: float = Field(0.75, ge=0.0, le=50.0)
    fix_interval_s: float = Field(9.0, gt=0.0, le=600.0)
    min_points: int = Field(60, ge=5, le=100000)
    # circle (Algorithm 1)
    inlier_threshold_m: float = Field(0.15, gt=0.0, le=10.0)
    failure_probability: float = Field(1e-3, gt=0.0, lt=1.0)
    inlier_proportion: float = Field(0.5, gt=0.0, lt=1.0)
    radius_tolerance_m: float = Field(0.5, ge=0.0, le=100.0, description="accepted |fitted - known| radius")
    # walls (IEPF, fuzzy segments)
    iepf_k_min: int = Field(8, ge=3, le=10000)
    iepf_rho_max_m: float = Field(0.2, gt=0.0, le=10.0)
    min_segment_length_m: float = Field(1.0, ge=0.0, le=1000.0)
    min_wall_support_m: float = Field(2.0, ge=0.0, le=1000.0, description="least extent of a fused wall estimate")
    heading_sigma_deg: float = Field(1.0, ge=0.0, le=45.0, description="heading sigma floor for the segments' uncertainty")
    map_match_angle_deg: float = Field(3.0, gt=0.0, le=45.0, description="fuzzy map collinearity angle (eq. 16)")
    map_min_match: float = Field(0.2, gt=0.0, le=1.0, description="fuzzy map matching-degree limit (eqs. 16-17)")
    map_motion_growth: float = Field(0.1, ge=0.0, le=10.0, description="95 % rho-cut growth per metre moved, m/m")
    map_age_growth_mps: float = Field(0.002, ge=0.0, le=10.0, description="95 % rho-cut growth per second, m/s")
    map_max_area_m: float = Field(1.0, gt=0.0, le=100.0, description="segments above this trapezoid area are removed")
    wall_match_angle_deg: float = Field(10.0, gt=0.0, le=45.0)
    wall_match_distance_m: float = Field(1.5, gt=0.0, le=100.0)
    wall_heading_fix: bool = Field(True, description="also fix the heading from the walls' known directions")
    wall_heading_sigma_floor_deg: float = Field(0.3, gt=0.0, le=45.0, description="added to the heading fix's sigma")
    fix_sigma_floor_m: float = Field(0.05, ge=0.0, le=10.0, description="added to each fix's sigma")
