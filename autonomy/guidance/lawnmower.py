"""Lawnmower (boustrophedon) survey planning over a rectangle in NED, and FLS swath width."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class LawnmowerPlan:
    """A planned survey.

    Attributes:
        waypoints_ne_m: (n, 2) waypoints, north/east, in visiting order.
        leg_starts_ne_m, leg_ends_ne_m: (n_legs, 2) straight survey legs (run-in included).
        leg_spacing_m: distance between adjacent legs, m.
        on_leg: (n,) bool, True where the segment *ending* at waypoint i is a survey leg.
    """

    waypoints_ne_m: FloatArray
    leg_starts_ne_m: FloatArray
    leg_ends_ne_m: FloatArray
    leg_spacing_m: float
    on_leg: NDArray[np.bool_]

    @property
    def n_legs(self) -> int:
        return int(self.leg_starts_ne_m.shape[0])

    def path_length_m(self) -> float:
        return float(np.sum(np.linalg.norm(np.diff(self.waypoints_ne_m, axis=0), axis=1)))


def fls_swath_width_m(
    altitude_m: float,
    tilt_rad: float,
    fov_rad: float,
    vertical_beam_rad: float,
    range_min_m: float,
    range_max_m: float,
    n_samples: int = 181,
) -> float:
    """Across-track width of the flat seabed a forward-looking sonar ensonifies.

    The sonar sits ``altitude_m`` above a flat seabed, boresight pitched down by
    ``tilt_rad``. A ray at azimuth ``a`` (|a| <= fov/2) and elevation ``phi``
    (|phi| <= vertical_beam/2, down positive) has the unit direction, in the level frame
    (x forward, y starboard, z down),
    ``[cos a cos phi cos g - sin phi sin g, sin a cos phi, cos a cos phi sin g + sin phi cos g]``
    with ``g`` the tilt; it meets the seabed at range ``h / d_z`` if that range lies in
    the window. The swath is twice the largest lateral offset ``r d_y`` over those rays.

    Returns:
        Swath width in m (0 when the seabed is not seen at all).
    """
    if not (altitude_m > 0.0 and range_max_m > range_min_m >= 0.0 and fov_rad > 0.0):
        raise ValueError("need altitude_m > 0, range_max_m > range_min_m >= 0 and fov_rad > 0")
    a = np.linspace(0.0, 0.5 * fov_rad, n_samples)[:, None]
    phi = np.linspace(-0.5 * vertical_beam_rad, 0.5 * vertical_beam_rad, n_samples)[None, :]
    g = tilt_rad
    d_y = np.sin(a) * np.cos(phi)
    d_z = np.cos(a) * np.cos(phi) * np.sin(g) + np.sin(phi) * np.cos(g)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(d_z > 0.0, altitude_m / d_z, np.inf)
    seen = (r >= range_min_m) & (r <= range_max_m)
    if not seen.any():
        return 0.0
    return float(2.0 * np.max(np.where(seen, r, 0.0) * d_y))


def _arc(center: FloatArray, start: FloatArray, end: FloatArray, n_points: int, turn_sign: float) -> FloatArray:
    """Points (excluding ``start``, including ``end``) on the semicircle from start to end,
    turning clockwise (seen from above in NED, i.e. to starboard) if ``turn_sign > 0``."""
    a0 = math.atan2(start[1] - center[1], start[0] - center[0])
    radius = float(np.linalg.norm(start - center))
    # In NED (north x, east y), increasing atan2(east, north) is clockwise seen from above.
    angles = a0 + turn_sign * np.linspace(0.0, math.pi, n_points + 1)[1:]
    pts = center + radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    pts[-1] = end
    return pts


def plan_lawnmower(
    origin_ne_m: tuple[float, float],
    length_m: float,
    width_m: float,
    leg_heading_rad: float,
    leg_spacing_m: float,
    first_turn: str = "starboard",
    run_in_m: float = 0.0,
    turn: str = "arc",
    min_turn_radius_m: float = 1.0,
    arc_points: int = 6,
) -> LawnmowerPlan:
    """Plan a lawnmower over a rectangle.

    Leg ``k`` runs parallel to ``leg_heading_rad`` (alternating direction), offset
    ``k * spacing`` across (to starboard of the first leg's direction, or port), for
    ``n_legs = ceil(width / spacing) + 1`` legs with the spacing shrunk so the last leg lies
    on the far edge. Each leg is extended by ``run_in_m`` at both ends. Turns are either
    corners (the connecting segment between legs) or semicircles of radius spacing/2 when
    that is at least ``min_turn_radius_m``.

    Returns:
        :class:`LawnmowerPlan`.
    """
    if not (length_m > 0.0 and width_m >= 0.0 and leg_spacing_m > 0.0 and run_in_m >= 0.0):
        raise ValueError("need length_m > 0, width_m >= 0, leg_spacing_m > 0, run_in_m >= 0")
    if first_turn not in ("starboard", "port"):
        raise ValueError(f"first_turn must be 'starboard' or 'port', got {first_turn!r}")
    if turn not in ("corner", "arc"):
        raise ValueError(f"turn must be 'corner' or 'arc', got {turn!r}")
    along = np.array([math.cos(leg_heading_rad), math.sin(leg_heading_rad)])
    side = 1.0 if first_turn == "starboard" else -1.0
    across = side * np.array([-along[1], along[0]])  # starboard of `along` in NED is (-e, n)
    n_legs = int(math.ceil(width_m / leg_spacing_m - 1e-9)) + 1 if width_m > 0.0 else 1
    spacing = width_m / (n_legs - 1) if n_legs > 1 else float(leg_spacing_m)
    origin = np.asarray(origin_ne_m, dtype=float)

    starts, ends = [], []
    for k in range(n_legs):
        base = origin + k * spacing * across
        a, b = base - run_in_m * along, base + (length_m + run_in_m) * along
        if k % 2:
            a, b = b, a
        starts.append(a)
        ends.append(b)

    use_arc = turn == "arc" and 0.5 * spacing >= min_turn_radius_m
    wps: list[FloatArray] = [starts[0], ends[0]]
    on_leg: list[bool] = [False, True]
    for k in range(1, n_legs):
        if use_arc:
            # Leg k-1 ends heading d; turning towards `across` is starboard iff side > 0
            # for even k-1 (heading along) and flips with each leg.
            heading_sign = 1.0 if (k - 1) % 2 == 0 else -1.0
            turn_sign = side * heading_sign
            center = 0.5 * (ends[k - 1] + starts[k])
            arc = _arc(center, ends[k - 1], starts[k], arc_points, turn_sign)
            wps.extend(arc)
            on_leg.extend([False] * len(arc))
        else:
            wps.append(starts[k])
            on_leg.append(False)
        wps.append(ends[k])
        on_leg.append(True)
    return LawnmowerPlan(
        waypoints_ne_m=np.array(wps),
        leg_starts_ne_m=np.array(starts),
        leg_ends_ne_m=np.array(ends),
        leg_spacing_m=float(spacing),
        on_leg=np.array(on_leg),
    )
