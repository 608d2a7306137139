"""Per-episode layout of ``auvsim/Survey-v1``: a square survey area larger than the sonar's
reach, the vehicle starting at its south-west corner, and the scenario's objects placed at
random in the area, out of the sonar's view from the start.

Everything is drawn from the generator given (the env's ``np_random``), so a seed fixes
the layout. The episode's scenario is the base scenario with its seabed enlarged to cover
the area plus the sonar's range, no basin walls, the drawn object positions, the start
pose, and a lawnmower plan over the area (the scripted baseline flies it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.guidance.lawnmower import fls_swath_width_m
from scenarios.schema import Scenario
from sim.envs.area import OperatingArea, survey_area
from sim.rng import component_rng
from sim.scene.seabed import Seabed, make_seabed
from scenarios.fls_presets import resolve_geometry
from scenarios.config.world import SeabedConfig

FloatArray = NDArray[np.float64]
START_INSET_M = 1.0  # start this far inside the south-west corner


@dataclass(frozen=True)
class SurveyLayout:
    """Fixed part of the layout (same every episode).

    Attributes:
        area: the surveyed square, NED.
        start_ned: (3,) start position, NED m (south-west corner, scenario start depth).
        start_yaw_rad: start heading (north, along the first lawnmower leg).
        sonar_reach_m: far edge of the sonar's range window, m.
        start_clearance_m: no object starts closer than this to the start, m.
        min_spacing_m: objects are at least this far apart, m.
        leg_spacing_m: lawnmower leg spacing of the reference plan, m.
    """

    area: OperatingArea
    start_ned: FloatArray
    start_yaw_rad: float
    sonar_reach_m: float
    start_clearance_m: float
    min_spacing_m: float
    leg_spacing_m: float


def make_layout(base: Scenario, size_ne_m: tuple[float, float], margin_m: float, *,
                start_clearance_m: float | None, min_spacing_m: float) -> SurveyLayout:
    """The area centred on the base scenario's survey plan, the start at its south-west
    corner, and lawnmower legs along both east and west edges and between them, spaced at
    most the sonar's swath at the survey altitude less 30 %.

    Raises:
        ValueError: an area not larger than the sonar's reach on both sides, or a clearance
            that leaves no room for the objects.
    """
    fls = base.sensors.fls
    g = resolve_geometry(fls)
    reach = float(g.window_far_m)
    size = np.asarray(size_ne_m, dtype=float)
    if not np.all(size > reach):
        raise ValueError(f"SurveyEnvOptions.area_size_ne_m {tuple(size)} must exceed the sonar's reach "
                         f"{reach:g} m on both sides")
    centre = survey_area(base, margin_m).center_ne_m
    area = OperatingArea(centre - 0.5 * size, centre + 0.5 * size, float(margin_m))
    clearance = reach + 5.0 if start_clearance_m is None else float(start_clearance_m)
    if clearance >= 0.9 * float(np.hypot(*size)):
        raise ValueError(f"start clearance {clearance:g} m leaves no room in a {tuple(size)} m area")
    survey = base.autonomy.guidance.survey
    swath = fls_swath_width_m(survey.altitude_m, math.radians(fls.tilt_deg), g.fov_rad, g.vertical_beamwidth_rad,
                              g.window_near_m, g.window_far_m)
    n_legs = math.ceil(float(size[1]) / (0.7 * swath)) + 1
    spacing = float(size[1]) / (n_legs - 1)
    start = np.array([area.lo_ne_m[0] + START_INSET_M, area.lo_ne_m[1] + START_INSET_M,
                      float(base.vehicle.initial_pos_ned[2])])
    return SurveyLayout(area, start, 0.0, reach, clearance, float(min_spacing_m), spacing)


def _seabed(base: Scenario, layout: SurveyLayout) -> dict:
    reach = layout.sonar_reach_m
    size = layout.area.hi_ne_m - layout.area.lo_ne_m
    seabed = base.world.seabed.model_dump()
    seabed["center_ne_m"] = tuple(float(x) for x in layout.area.center_ne_m)
    seabed["extent_m"] = float(np.max(size) + 2.0 * (layout.area.margin_m + reach))
    return seabed


def episode_seabed(base: Scenario, layout: SurveyLayout) -> Seabed:
    """The episode seabed (the same every episode: it depends on the scenario's seed only)."""
    return make_seabed(SeabedConfig.model_validate(_seabed(base, layout)), component_rng(base.seed, "seabed"))


def draw_positions_ne(layout: SurveyLayout, n: int, rng: np.random.Generator, max_tries: int = 10000) -> FloatArray:
    """(n, 2) object positions, uniform in the area (1 m inside its edges), at least
    ``start_clearance_m`` from the start and ``min_spacing_m`` from each other.

    Raises:
        ValueError: the constraints could not be met in ``max_tries`` draws.
    """
    lo, hi = layout.area.lo_ne_m + 1.0, layout.area.hi_ne_m - 1.0
    out: list[FloatArray] = []
    for _ in range(max_tries):
        if len(out) == n:
            break
        p = rng.uniform(lo, hi)
        if np.hypot(*(p - layout.start_ned[:2])) < layout.start_clearance_m:
            continue
        if any(np.hypot(*(p - q)) < layout.min_spacing_m for q in out):
            continue
        out.append(p)
    if len(out) < n:
        raise ValueError(f"could not place {n} objects {layout.min_spacing_m:g} m apart and "
                         f"{layout.start_clearance_m:g} m from the start")
    return np.array(out, dtype=float).reshape(n, 2)


def episode_scenario(base: Scenario, layout: SurveyLayout, seabed: Seabed, rng: np.random.Generator) -> Scenario:
    """The base scenario laid out for one episode (objects drawn from ``rng``)."""
    base_seabed = make_seabed(base.world.seabed, component_rng(base.seed, "seabed"))
    data = base.model_dump()
    positions = draw_positions_ne(layout, len(base.world.targets), rng)
    yaws = rng.uniform(-180.0, 180.0, len(base.world.targets))
    targets = []
    for t, (n, e), yaw in zip(data["world"]["targets"], positions, yaws):
        # keep each object's height above (or burial below) the seabed it was placed on
        offset = float(t["pos_ned"][2]) - float(base_seabed.depth_at(t["pos_ned"][0], t["pos_ned"][1]))
        t["pos_ned"] = (float(n), float(e), float(seabed.depth_at(n, e)) + offset)
        roll, pitch, yaw0 = t["rpy_deg"]
        t["rpy_deg"] = (roll, pitch, float(yaw0 + yaw))
        targets.append(t)
    data["world"]["targets"] = targets
    data["world"]["seabed"] = _seabed(base, layout)
    data["world"]["basin"] = {**data["world"]["basin"], "shape": "none"}
    data["vehicle"]["initial_pos_ned"] = tuple(float(x) for x in layout.start_ned)
    data["vehicle"]["initial_rpy_deg"] = (0.0, 0.0, math.degrees(layout.start_yaw_rad))
    # the plan (legs and their semicircular turns) spans the area, which also bounds the
    # onboard world model's region
    size = layout.area.hi_ne_m - layout.area.lo_ne_m
    half = 0.5 * layout.leg_spacing_m
    survey = data["autonomy"]["guidance"]["survey"]
    survey.update(origin_ne_m=(float(layout.area.lo_ne_m[0] + half), float(layout.area.lo_ne_m[1])),
                  leg_heading_deg=0.0, length_m=float(size[0] - 2.0 * half), width_m=float(size[1]),
                  first_turn="starboard", leg_spacing_m=layout.leg_spacing_m, run_in_m=0.0, turn="arc")
    return Scenario.model_validate(data)
