"""Placement checks a scenario must pass before anything is built.

Field validation checks each value alone; these checks relate values to each other: the
vehicle starts in the water, above the seabed, inside the seabed patch and the basin
walls; each target sits in the water, not above the surface nor buried below the seabed,
inside the patch and the walls; no two targets overlap; an extra vehicle (a surface buoy)
starts inside the walls, over water deeper than its keel, clear of the AUV, the targets and
the other vehicles. Depths are NED z (m, positive
down); the seabed depth is the plane (or slope) through ``seabed.depth_m`` at
``seabed.center_ne_m``; rough and ripple seabeds are allowed their relief on top.
"""

from __future__ import annotations

import math

import numpy as np

from scenarios.config.world import DEBRIS_TARGET_SHAPES
from scenarios.schema import Scenario
from scenarios.vehicle_presets import surface_hull_span_m, vehicle_envelope_m, vehicle_half_height_m
from scenarios.bathymetry import bathymetry_problems

# Relief allowed around the mean plane of a rough seabed, in rms heights (a Gaussian field
# exceeds 4 sigma on about 6e-5 of its area).
ROUGH_RELIEF_SIGMAS = 4.0
# How far above the surface (negative depth) a vehicle may start, m.
MAX_START_ABOVE_SURFACE_M = 1.0


def seabed_mean_depth_m(scenario: Scenario, n_m: float, e_m: float) -> float:
    """Depth (NED z, m) of the seabed's mean plane under (north, east)."""
    c = scenario.world.seabed
    if c.kind == "plane" or c.slope_deg == 0.0:
        return float(c.depth_m)
    az = math.radians(c.slope_azimuth_deg)
    k = math.tan(math.radians(c.slope_deg))
    return float(c.depth_m + k * ((n_m - c.center_ne_m[0]) * math.cos(az) + (e_m - c.center_ne_m[1]) * math.sin(az)))


def seabed_relief_m(scenario: Scenario) -> float:
    """Largest expected height of the seabed above or below its mean plane, m."""
    c = scenario.world.seabed
    if c.kind == "rough":
        return ROUGH_RELIEF_SIGMAS * c.roughness_m
    if c.kind == "ripple":
        return c.ripple_amplitude_m
    return 0.0


def _target_height_m(t) -> float:
    """Height of a target above its base (upright; a debris shape in its default pose), m."""
    if t.shape in DEBRIS_TARGET_SHAPES:
        return t.size_m[2]
    return {"half_sphere": t.radius_m, "truncated_cone": t.height_m, "cylinder": t.height_m,
            "box": t.size_m[2], "tyre": 2.0 * t.tube_radius_m}[t.shape]


def _inscribed_radius_m(t) -> float:
    """Radius of a circle about the base centre that lies inside the target's footprint, m
    (a debris shape's: a quarter of its box's smaller side, a hook's bar radius)."""
    if t.shape == "hook":
        return 0.5 * t.size_m[2]
    if t.shape in DEBRIS_TARGET_SHAPES:
        return 0.25 * min(t.size_m[0], t.size_m[1])
    return t.radius_m if t.shape != "box" else 0.5 * min(t.size_m[0], t.size_m[1])


def _inscribed_footprint(t) -> np.ndarray:
    """Convex (k, 2) north-east polygon inside the target's footprint (for overlap: only a
    certain overlap is reported): an upright box's rotated rectangle, else an inscribed circle."""
    n0, e0 = t.pos_ned[0], t.pos_ned[1]
    roll, pitch, yaw = (math.radians(a) for a in t.rpy_deg)
    if t.shape == "box" and abs(roll) < 1e-9 and abs(pitch) < 1e-9:
        hx, hy = 0.5 * t.size_m[0], 0.5 * t.size_m[1]
        local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
        c, s = math.cos(yaw), math.sin(yaw)
        return local @ np.array([[c, -s], [s, c]]).T + np.array([n0, e0])
    a = np.linspace(0.0, 2.0 * math.pi, 24, endpoint=False)
    return np.array([n0, e0]) + _inscribed_radius_m(t) * np.c_[np.cos(a), np.sin(a)]


def convex_polygons_overlap(a: np.ndarray, b: np.ndarray, tol_m: float = 1e-6) -> bool:
    """Whether two convex polygons ((k, 2) vertices in order) overlap by more than ``tol_m``.

    Separating-axis theorem: they are apart iff some edge normal separates them.
    """
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.c_[-edges[:, 1], edges[:, 0]]
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        pa, pb = a @ normals.T, b @ normals.T
        if np.any((pa.max(axis=0) <= pb.min(axis=0) + tol_m) | (pb.max(axis=0) <= pa.min(axis=0) + tol_m)):
            return False
    return True


def _inside_basin(scenario: Scenario, n_m: float, e_m: float, margin_m: float) -> bool:
    b = scenario.world.basin
    if b.shape == "rectangular":
        return (abs(n_m - b.center_ne_m[0]) <= 0.5 * b.size_ne_m[0] - margin_m
                and abs(e_m - b.center_ne_m[1]) <= 0.5 * b.size_ne_m[1] - margin_m)
    if b.shape == "circular":
        return math.hypot(n_m - b.center_ne_m[0], e_m - b.center_ne_m[1]) <= b.radius_m - margin_m
    return True


def _inside_patch(scenario: Scenario, n_m: float, e_m: float) -> bool:
    c = scenario.world.seabed
    half = 0.5 * c.extent_m
    return abs(n_m - c.center_ne_m[0]) <= half and abs(e_m - c.center_ne_m[1]) <= half


def _extra_vehicle_problems(scenario: Scenario, relief_m: float) -> list[str]:
    """Each extra vehicle (``vehicles.<name>``) starts inside the patch and the walls, afloat
    over water deeper than its keel, clear of the AUV, of every target and of the others."""
    problems: list[str] = []
    wall_margin = 0.5 * scenario.world.basin.wall_thickness_m
    an, ae, ad = scenario.vehicle.initial_pos_ned
    length, width, height = vehicle_envelope_m(scenario.vehicle.model)
    auv_r, auv_top = 0.5 * math.hypot(length, width), ad - 0.5 * height
    placed: list[tuple[str, float, float, float]] = []
    for name, v in scenario.vehicles.items():
        key = f"vehicles.{name}.initial_pos_ne_m"
        n, e = v.initial_pos_ne_m
        r, top, keel = surface_hull_span_m(v.preset)
        if not _inside_patch(scenario, n, e):
            problems.append(f"{key}: ({n:g}, {e:g}) m lies outside the seabed patch")
            continue
        if not _inside_basin(scenario, n, e, wall_margin + r):
            problems.append(f"{key}: ({n:g}, {e:g}) m puts the hull ({r:.2f} m from its centre) into the basin "
                            "walls (world.basin)")
        bed = seabed_mean_depth_m(scenario, n, e) - relief_m
        if keel >= bed:
            problems.append(f"{key}: the keel ({keel:.2f} m deep) touches the seabed ({bed:.2f} m) there")
        apart = math.hypot(n - an, e - ae)
        if apart < r + auv_r and auv_top < keel:
            problems.append(f"{key}: overlaps the AUV at its start (vehicle.initial_pos_ned, {apart:.2f} m apart, "
                            f"at least {r + auv_r:.2f} m needed)")
        for i, t in enumerate(scenario.world.targets):
            tn, te, tz = t.pos_ned
            if math.hypot(tn - n, te - e) < _inscribed_radius_m(t) + r and tz - _target_height_m(t) < keel:
                problems.append(f"{key}: overlaps world.targets.{i} ({t.name})")
        for other, on, oe, orad in placed:
            if math.hypot(on - n, oe - e) < r + orad:
                problems.append(f"{key}: overlaps vehicles.{other}")
        placed.append((name, n, e, r))
    return problems


def survey_corners_ne(scenario: Scenario) -> np.ndarray:
    """(4, 2) north-east corners of the lawnmower area, run-in included, m."""
    sv = scenario.autonomy.guidance.survey
    h = math.radians(sv.leg_heading_deg)
    along = np.array([math.cos(h), math.sin(h)])
    side = 1.0 if sv.first_turn == "starboard" else -1.0
    across = side * np.array([-math.sin(h), math.cos(h)])
    o = np.asarray(sv.origin_ne_m, dtype=float)
    a0, a1 = -sv.run_in_m, sv.length_m + sv.run_in_m
    return np.array([o + a0 * along, o + a1 * along, o + a1 * along + sv.width_m * across,
                     o + a0 * along + sv.width_m * across])


def _survey_problems(scenario: Scenario, relief_m: float) -> list[str]:
    """The survey area must lie over the seabed, inside the walls, and its altitude or depth
    must put the hull in the water above the seabed everywhere."""
    sv = scenario.autonomy.guidance.survey
    key = "autonomy.guidance.survey"
    corners = survey_corners_ne(scenario)
    margin = 0.5 * scenario.world.basin.wall_thickness_m
    out = [c for c in corners if not _inside_patch(scenario, *c)]
    if out:
        return [f"{key}: the survey area (corner {tuple(round(float(v), 2) for v in out[0])} m) reaches past the "
                "seabed patch (world.seabed extent_m / center_ne_m)"]
    problems = []
    if any(not _inside_basin(scenario, *c, margin) for c in corners):
        problems.append(f"{key}: the survey area reaches past the basin walls (world.basin); move origin_ne_m or "
                        "shrink length_m / width_m")
    half_h = vehicle_half_height_m(scenario.vehicle.model)
    shallowest = min(seabed_mean_depth_m(scenario, *c) for c in corners) - relief_m
    if sv.vertical_mode == "altitude" and sv.altitude_m + half_h >= shallowest:
        problems.append(f"{key}.altitude_m: {sv.altitude_m:g} m above the seabed is out of the water where the "
                        f"seabed is {shallowest:.2f} m deep (the hull needs {half_h:.2f} m below the surface)")
    if sv.vertical_mode == "depth" and sv.depth_m + half_h >= shallowest:
        problems.append(f"{key}.depth_m: {sv.depth_m:g} m is at or below the seabed, {shallowest:.2f} m deep "
                        "in the survey area")
    return problems


def placement_problems(scenario: Scenario) -> list[str]:
    """Every impossible placement in ``scenario``, one message each (empty if none)."""
    if scenario.world.seabed.kind == "file":
        return bathymetry_problems(scenario)
    problems: list[str] = []
    relief = seabed_relief_m(scenario)
    basin = scenario.world.basin
    wall_margin = 0.5 * basin.wall_thickness_m

    n, e, d = scenario.vehicle.initial_pos_ned
    key = "vehicle.initial_pos_ned"
    if not _inside_patch(scenario, n, e):
        problems.append(f"{key}: ({n:g}, {e:g}) m lies outside the seabed patch "
                        f"(world.seabed: {scenario.world.seabed.extent_m:g} m square centred at "
                        f"{tuple(scenario.world.seabed.center_ne_m)})")
    elif not _inside_basin(scenario, n, e, wall_margin):
        problems.append(f"{key}: ({n:g}, {e:g}) m lies outside the basin walls (world.basin)")
    else:
        bed = seabed_mean_depth_m(scenario, n, e)
        half_h = vehicle_half_height_m(scenario.vehicle.model)
        if d + half_h > bed - relief:
            problems.append(f"{key}: depth {d:g} m puts the hull (half height {half_h:.2f} m) into the seabed "
                            f"at {bed - relief:.2f} m there")
    if d < -MAX_START_ABOVE_SURFACE_M:
        problems.append(f"{key}: depth {d:g} m is above the surface (NED z is positive down)")

    targets = scenario.world.targets
    for i, t in enumerate(targets):
        key = f"world.targets.{i} ({t.name})"
        tn, te, tz = t.pos_ned
        if not _inside_patch(scenario, tn, te):
            problems.append(f"{key}: ({tn:g}, {te:g}) m lies outside the seabed patch")
            continue
        if not _inside_basin(scenario, tn, te, wall_margin):
            problems.append(f"{key}: ({tn:g}, {te:g}) m lies outside the basin walls (world.basin)")
        bed = seabed_mean_depth_m(scenario, tn, te)
        top = tz - _target_height_m(t)
        if tz < 0.0:
            problems.append(f"{key}: base depth {tz:g} m is above the surface (NED z is positive down; "
                            f"the seabed is at {bed:.2f} m there)")
        elif top > bed + relief + 1e-6:
            problems.append(f"{key}: buried below the seabed (its top at {top:.2f} m, the seabed at {bed:.2f} m)")
    problems += _survey_problems(scenario, relief)
    length, width, height = vehicle_envelope_m(scenario.vehicle.model)
    hull_r = 0.5 * math.hypot(length, width)
    for i, t in enumerate(targets):
        tn, te, tz = t.pos_ned
        inscribed = _inscribed_radius_m(t)
        apart_m = math.hypot(tn - n, te - e)
        hull_bottom = d + 0.5 * height
        if apart_m < inscribed + hull_r and hull_bottom > tz - _target_height_m(t):
            problems.append(f"world.targets.{i} ({t.name}): overlaps the vehicle at its start "
                            f"(vehicle.initial_pos_ned, {apart_m:.2f} m apart)")
    problems += _extra_vehicle_problems(scenario, relief)
    polys = [_inscribed_footprint(t) for t in targets]
    for i in range(len(targets)):
        for j in range(i + 1, len(targets)):
            if convex_polygons_overlap(polys[i], polys[j]):
                problems.append(f"world.targets.{i} ({targets[i].name}) and world.targets.{j} ({targets[j].name}) "
                                "overlap")
    return problems
