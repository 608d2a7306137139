"""The operating area of a gym episode: the scenario's survey rectangle in NED."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.guidance.lawnmower import fls_swath_width_m
from autonomy.guidance.survey import plan_from_config
from scenarios.schema import Scenario
from scenarios.fls_presets import resolve_geometry

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class OperatingArea:
    """Axis-aligned north/east box, m.

    Attributes:
        lo_ne_m, hi_ne_m: (2,) south-west and north-east corners of the surveyed area.
        margin_m: how far outside the box the vehicle may go before the episode ends.
    """

    lo_ne_m: FloatArray
    hi_ne_m: FloatArray
    margin_m: float

    @property
    def center_ne_m(self) -> FloatArray:
        return 0.5 * (self.lo_ne_m + self.hi_ne_m)

    @property
    def half_size_ne_m(self) -> FloatArray:
        return 0.5 * (self.hi_ne_m - self.lo_ne_m)

    def contains(self, pos_ne_m: NDArray, *, with_margin: bool = True) -> bool:
        m = self.margin_m if with_margin else 0.0
        p = np.asarray(pos_ne_m, dtype=float)[:2]
        return bool(np.all(p >= self.lo_ne_m - m) and np.all(p <= self.hi_ne_m + m))


def survey_area(scenario: Scenario, margin_m: float) -> OperatingArea:
    """Bounding box of the scenario's lawnmower plan (``autonomy.guidance.survey``)."""
    if not margin_m >= 0.0:
        raise ValueError(f"area margin_m must be >= 0, got {margin_m}")
    survey = scenario.autonomy.guidance.survey
    swath = None
    if survey.leg_spacing_m == "from_swath":
        g = resolve_geometry(scenario.sensors.fls)
        swath = fls_swath_width_m(survey.altitude_m, np.deg2rad(scenario.sensors.fls.tilt_deg), g.fov_rad,
                                  g.vertical_beamwidth_rad, g.window_near_m, g.window_far_m)
    wps = np.asarray(plan_from_config(survey, swath).waypoints_ne_m, dtype=float)
    lo, hi = wps.min(axis=0), wps.max(axis=0)
    hi = np.maximum(hi, lo + 1.0)  # a single leg still spans a box
    return OperatingArea(lo, hi, float(margin_m))
