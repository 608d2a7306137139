"""Aborts a scenario makes certain before it runs: a survey flown outside the mission's own
safety limits (``autonomy.guidance.mission``).

The mission state machine (:mod:`autonomy.guidance.mission`) aborts when the navigation
depth is below ``safe_depth_max_m`` (any state) or, while surveying, above
``safe_depth_min_m``, and when the altitude is under ``min_altitude_m``. A lawnmower whose
commanded altitude or depth already breaks one of these limits aborts as soon as it gets
there (exit status 3, after the dive); this module finds those at load, so ``auvsim
validate`` and ``auvsim run`` refuse them in one line per survey setting naming the keys.

The seabed depth over the survey is the mean surface (plane or slope through
``world.seabed.depth_m``, :func:`scenarios.placement.seabed_mean_depth_m`) at the corners of
the survey area; a measured depth grid (``kind: file``) is not read here, so with it only the
checks that need no seabed are made. Equal values are allowed (the vehicle holds the limit).
"""

from __future__ import annotations

from scenarios.schema import Scenario

SURVEY = "autonomy.guidance.survey"
MISSION = "autonomy.guidance.mission"


def _bed_range_m(scenario: Scenario) -> tuple[float, float] | None:
    """(shallowest, deepest) mean seabed depth at the survey area's corners, m; None for a
    measured depth grid."""
    if scenario.world.seabed.kind == "file":
        return None
    from scenarios.placement import seabed_mean_depth_m, survey_corners_ne

    depths = [seabed_mean_depth_m(scenario, float(n), float(e)) for n, e in survey_corners_ne(scenario)]
    return min(depths), max(depths)


def mission_limit_problems(scenario: Scenario) -> list[str]:
    """One message per survey setting (``altitude_m`` or ``depth_m``, by ``vertical_mode``)
    that puts the survey past a limit of ``autonomy.guidance.mission``, and for a start deeper
    than ``safe_depth_max_m``; empty if none. A buddy-observer scenario
    (``autonomy.guidance.buddy.enabled``) flies no survey: only its start is checked.

    Each message starts with the survey key and its value and names every limit it breaks
    with its value (``<key> (<value> m)``), so ``--set`` overrides of either key are credited.
    """
    g = scenario.autonomy.guidance
    p, sv = g.mission, g.survey
    problems: list[str] = []
    start_depth = float(scenario.vehicle.initial_pos_ned[2])
    if start_depth > p.safe_depth_max_m:
        problems.append(f"vehicle.initial_pos_ned: the start depth {start_depth:g} m is below {MISSION}.safe_depth_max_m "
                        f"({p.safe_depth_max_m:g} m): the mission would abort at once")
    if g.buddy.enabled:
        return problems
    beds = _bed_range_m(scenario)
    broken: list[str] = []
    if sv.vertical_mode == "altitude":
        key, value = f"{SURVEY}.altitude_m", sv.altitude_m
        if sv.altitude_m < p.min_altitude_m:
            broken.append(f"below {MISSION}.min_altitude_m ({p.min_altitude_m:g} m)")
        if beds is not None:
            shallow, deep = beds[0] - sv.altitude_m, beds[1] - sv.altitude_m
            if deep > p.safe_depth_max_m:
                broken.append(f"{deep:.2f} m deep over the {beds[1]:.2f} m seabed, below {MISSION}.safe_depth_max_m "
                              f"({p.safe_depth_max_m:g} m)")
            if 0.0 <= shallow < p.safe_depth_min_m:  # out of the water: a placement problem
                broken.append(f"{shallow:.2f} m deep over the {beds[0]:.2f} m seabed, above "
                              f"{MISSION}.safe_depth_min_m ({p.safe_depth_min_m:g} m)")
    else:
        key, value = f"{SURVEY}.depth_m", sv.depth_m
        if sv.depth_m > p.safe_depth_max_m:
            broken.append(f"below {MISSION}.safe_depth_max_m ({p.safe_depth_max_m:g} m)")
        if sv.depth_m < p.safe_depth_min_m:
            broken.append(f"above {MISSION}.safe_depth_min_m ({p.safe_depth_min_m:g} m)")
        if beds is not None and 0.0 <= beds[0] - sv.depth_m < p.min_altitude_m:  # below: a placement problem
            broken.append(f"{beds[0] - sv.depth_m:.2f} m above the {beds[0]:.2f} m seabed, below "
                          f"{MISSION}.min_altitude_m ({p.min_altitude_m:g} m)")
    if broken:
        problems.append(f"{key} ({value:g} m) would abort the mission once the survey reaches it: "
                        f"{'; '.join(broken)}; change the survey or the limits")
    return problems
